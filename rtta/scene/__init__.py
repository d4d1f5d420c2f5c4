"""Scene layer: what is drawn, before any GL.

Loading files (what may be read: `files`; declared sizes: `precheck`; every format's
reader in `readers/`: glTF checked, its node graph walked and rewritten for trimesh, OBJ,
Draco, and the assemblies with their part tree: STEP, IFC, COLLADA, USD, 3DXML;
preprocessing of vertices and normals, textures and the material atlas they are packed
into), the
batched `Scene` (one vertex/index buffer, a per-vertex object id; each object's path in the
tree, the unit and up axis), names, groups and globs resolved to objects (`select`), the
orbit `Camera`; generated scenes and the demo in `generators/`. The bottom layer: it
imports only `rtta.errors` and `rtta.outputs`.
"""

from .camera import Camera
from .loader import load_scene, load_scene_or_demo
from .model import Scene, from_meshes

__all__ = ["Camera", "Scene", "from_meshes", "load_scene", "load_scene_or_demo"]
