"""The desktop viewer (moderngl-window + imgui-bundle) built on the rtta library; see issue 4."""
