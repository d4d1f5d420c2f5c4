#!/usr/bin/env bash
# The benchmarks and the GL tests on a machine with a GPU, through EGL, in one command that
# ends well inside a lease: scripts/bench_device.sh [--local] [STEP ...]
# STEPs (default: all, in this order): snapshots capture composite frame tests tiny profile viewer
# viewer_tests scale; on request also profile100k (a 100,000-part frame under cProfile) and
# timers (GPU time per stage from timer queries, 10,000 and 100,000 parts), stages (per dispatch),
# demo (the demo's dispatches and draws), kick (the flushes between stages against none)
# and blends (the compute blend against sprites).
#
# Made for this workplace's `device` tool, whose machines have an NVIDIA driver and Python
# 3.12 with numpy, scipy, pillow, pytest and pytest-xdist but no GL loader and no rtta: it
# unpacks the libglvnd packages carried in .gl/ and installs the wheels carried in .whl/
# (moderngl, glcontext, trimesh, pycollada, rtree and rtta itself, built here by
# `pip wheel --no-deps -w .whl .`; for the viewer step also moderngl-window, pyglet,
# imgui-bundle and their needs: pyglm, munch, glfw, PyOpenGL, pydantic, pydantic-core,
# annotated-types, typing-inspection: 43 MB in all). Scenes from ../shared/data come in .gpudata/.
# Every step has its own time limit and a failing step does not stop the next; the log goes
# to $OUT/log. --local runs the same steps here (llvmpipe), to check the script.
set -uo pipefail
OUT=${OUT:-/tmp/bench_device_out}
mkdir -p "$OUT"
exec > >(tee "$OUT/log") 2>&1
export PYTHONUNBUFFERED=1

if [[ "${1:-}" != "--local" ]]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
    vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
    [ -e $vendor ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$vendor
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site PATH=/tmp/site/bin:$PATH
    # the tests run the command beside their interpreter, as in a virtual environment
    for exe in rtta rtta-view; do
        ln -sf /tmp/site/bin/$exe "$(dirname "$(readlink -f "$(command -v python3)")")/$exe"
        ln -sf /tmp/site/bin/$exe "$(dirname "$(command -v python3)")/$exe"
    done
    XDIST="-n 12"
else
    shift
    XDIST=
fi
STEPS=${*:-snapshots capture composite frame tests tiny profile viewer viewer_tests scale}
ROOT=$PWD DATA=$PWD/.gpudata TESTS=$PWD/tests
# the tests look for the shared scenes beside the checkout (../shared/data): the carried ones there
[ -e "$ROOT/../shared/data" ] || { mkdir -p "$ROOT/../shared" && ln -s "$DATA" "$ROOT/../shared/data"; }
cd /tmp        # import the installed rtta (with its shaders and assets), not the checkout's

step() {    # step SECONDS NAME COMMAND...
    local limit=$1 name=$2; shift 2
    echo "=== $name (limit ${limit}s) $(date +%T)"
    local t0=$SECONDS
    timeout --signal=INT --kill-after=10 "$limit" "$@"
    local rc=$?
    echo "=== $name: rc $rc in $((SECONDS - t0)) s"
    return $rc
}
wanted() { [[ " $STEPS " == *" $1 "* ]]; }

# A driver that gives no context ends the run here, at a few seconds' cost.
step 30 glinfo python3 -c "
from rtta.gl.context import shared_context, Capabilities
ctx = shared_context(); c = Capabilities.of(ctx)
for k in ('GL_RENDERER', 'GL_VERSION', 'GL_VENDOR'): print(k, ctx.info[k])
print('capture path', c.capture_path(), 'max layers', c.max_layers, 'max texture', c.max_texture)
" || exit 1
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv

# The pictures, to look at: every mode of the demo and the engine's ghosted-ao, one PNG.
wanted snapshots && step 60 snapshots bash -c "python3 -m rtta snapshot --all-modes /tmp/modes --size 512x512 \
    --focus \$(python3 -m rtta info | awk 'NR==3{print \$2}') && python3 -m rtta snapshot '$DATA/engine_2cyl.glb' \
    --mode ghosted-ao --size 512x512 --out /tmp/modes/zengine.png && python3 -c \"
import glob; from PIL import Image
ims = [Image.open(f).convert('RGB') for f in sorted(glob.glob('/tmp/modes/*.png'))]
m = Image.new('RGB', (512 * len(ims), 512)); [m.paste(im, (512 * i, 0)) for i, im in enumerate(ims)]
m.save('$OUT/modes.png')\""
wanted capture && step 60 capture python3 -m rtta bench capture --json "$OUT/capture.json"
wanted composite && step 90 composite python3 -m rtta bench composite --scene demo "$DATA/engine_2cyl.glb" \
    "$DATA/cycloidal.glb" table1-580 --json "$OUT/composite.json"
GL_TESTS="api batch blend_tiles bounds capture capture_lists capture_outputs closure composite composite_gpu explode export extremes
    gl_features glsl gpu_frame gpu_parameterize importance ldi lens material outline_sprites pixel_order post projector
    references sections targets thin_gpu views wrong_pictures"
# The GPU-driven frame against the CPU path: Python, wall and GPU ms per stage (issue 43).
wanted frame && step 150 frame python3 -m rtta bench frame --parts 1000,10000,100000 --scene "$DATA/engine_2cyl.glb" \
    --json "$OUT/frame.json"
wanted tests && step 200 tests python3 -m pytest -q --tb=short -p no:cacheprovider $XDIST --maxfail=30 \
    $(for t in $GL_TESTS; do echo "$TESTS/test_$t.py"; done)
wanted tiny && step 60 tiny python3 "$ROOT/scripts/probe_tiny.py"
wanted profile && step 120 profile bash -c "python3 '$ROOT/scripts/profile_frame.py' --frames 200 --top 25 &&
    python3 -c \"from rtta.scene.generators.assembly import write_assembly; write_assembly('/tmp/asm10k.glb', 10000)\" &&
    python3 '$ROOT/scripts/profile_frame.py' /tmp/asm10k.glb --mode ghosted --size 1280x720 --frames 40 --top 25"
wanted profile100k && step 150 profile100k bash -c "
    python3 -c \"from rtta.scene.generators.assembly import write_assembly; write_assembly('/tmp/asm100k.glb', 100000)\" &&
    python3 '$ROOT/scripts/profile_frame.py' /tmp/asm100k.glb --mode ghosted --size 1280x720 --frames ${PROFILE_FRAMES:-10} --top 30"
wanted timers && step 150 timers bash -c "
    python3 -c \"from rtta.scene.generators.assembly import write_assembly as w; w('/tmp/asm10k.glb', 10000); w('/tmp/asm100k.glb', 100000)\" &&
    for f in /tmp/asm10k.glb /tmp/asm100k.glb; do for opt in '' --sync '--sync --no-hull'; do
        python3 '$ROOT/scripts/gpu_timers.py' \$f \$opt; done; done"
# GPU time per compute dispatch and per draw, GPU path (and 10,000 parts on the CPU path).
wanted stages && step 150 stages bash -c "
    python3 -c \"from rtta.scene.generators.assembly import write_assembly as w; w('/tmp/asm1k.glb', 1000); w('/tmp/asm10k.glb', 10000); w('/tmp/asm100k.glb', 100000)\" &&
    for f in /tmp/asm1k.glb /tmp/asm10k.glb /tmp/asm100k.glb '$DATA/engine_2cyl.glb'; do python3 '$ROOT/scripts/gpu_timers.py' \$f --stages; done &&
    for f in /tmp/asm1k.glb '$DATA/engine_2cyl.glb'; do python3 '$ROOT/scripts/gpu_timers.py' \$f --stages --fused-max 0; done &&
    python3 '$ROOT/scripts/gpu_timers.py' /tmp/asm10k.glb --stages --parameterize cpu"
# The demo's frame, 1024²: GPU ms per dispatch and draw of ghosted and ghosted-ao, both paths.
wanted demo && step 90 demo bash -c "for m in ghosted ghosted-ao; do for p in gpu cpu; do
    python3 '$ROOT/scripts/gpu_timers.py' --mode \$m --size 1024x1024 --stages --parameterize \$p; done; done &&
    for opt in --sync '--sync --no-hull' '--sync --fused-max 0'; do
    python3 '$ROOT/scripts/gpu_timers.py' --mode ghosted-ao --size 1024x1024 --stages \$opt; done"
# The frame's flushes between stages (sync.kick) against none, on the demo, paired runs.
wanted kick && step 60 kick bash -c "for k in off on off on; do python3 -c \"
import rtta.gl.sync as s
if '\$k' == 'off': s.kick = lambda ctx: None
from rtta.cli.main import main
print('kick \$k'); main(['bench', 'composite', '--scene', 'demo'])\"; done"
# The compute blend against the sprites it replaces (Settings.blend), GPU ms per stage, SPAN 1, 2, 4.
wanted blends && step 120 blends bash -c "
    python3 -c \"from rtta.scene.generators.assembly import write_assembly as w; w('/tmp/asm1k.glb', 1000); w('/tmp/asm10k.glb', 10000); w('/tmp/asm100k.glb', 100000)\" &&
    for f in /tmp/asm1k.glb /tmp/asm10k.glb /tmp/asm100k.glb; do python3 '$ROOT/scripts/gpu_timers.py' \$f \
        --blends raster,compute:1,compute:2,compute:4; done"
# The viewer in pyglet's headless window: the demo, then 10,000 parts with and without fast navigation.
wanted viewer && step 150 viewer bash -c "rtta-view --bench 20 --bench-modes ghosted,ghosted-ao &&
    python3 -m rtta bench scale --parts 10000 --json '$OUT/scale_viewer.json'"
# The viewer's tests, driven in the headless window (the tree viewer's need ifcopenshell: not there).
wanted viewer_tests && step 150 viewer_tests env RTTA_TEST_HEADLESS=1 python3 -m pytest -q --tb=short \
    -p no:cacheprovider $XDIST "$TESTS/test_viewer.py"
# Last: the 100,000-part row may not finish; the rows before it print as they finish.
wanted scale && step 200 scale python3 -m rtta bench scale --no-viewer --parts 1000,10000,100000 \
    --json "$OUT/scale.json"
echo "=== done $(date +%T)"
