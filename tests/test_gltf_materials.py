"""Older glTF materials (KHR_materials_pbrSpecularGlossiness): the diffuse factor and
texture are the base colour, over the metallic-roughness fallback the file also carries."""

from __future__ import annotations

import numpy as np
from bad_gltf import box_doc, glb, png

from rtta.scene.loader import load_scene


def _box_with(material: dict, tmp_path, image: bytes | None = None, texture: dict | None = None):
    doc, binary = box_doc()
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["materials"] = [material]
    if image is not None:
        uv = np.zeros((24, 2), np.float32)
        doc["bufferViews"] += [
            {"buffer": 0, "byteOffset": len(binary), "byteLength": uv.nbytes},
            {"buffer": 0, "byteOffset": len(binary) + uv.nbytes, "byteLength": len(image)},
        ]
        binary += uv.tobytes() + image + b"\0" * (-len(image) % 4)
        doc["buffers"][0]["byteLength"] = len(binary)
        doc["accessors"].append({"bufferView": 3, "componentType": 5126, "count": 24, "type": "VEC2"})
        doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 3
        doc["textures"] = [texture if texture is not None else {"source": 0}]
        doc["images"] = [{"bufferView": 4, "mimeType": "image/png"}]
    path = tmp_path / "box.glb"
    path.write_bytes(glb(doc, binary))
    return load_scene(path)


def test_specular_glossiness_diffuse_is_the_base_colour(tmp_path):
    spec_gloss = {"diffuseFactor": [0.9, 0.1, 0.1, 1.0], "specularFactor": [0.2, 0.2, 0.2]}
    material = {
        "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.9, 0.1, 1.0]},
        "extensions": {"KHR_materials_pbrSpecularGlossiness": spec_gloss},
    }
    scene = _box_with(material, tmp_path)
    red = _box_with({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1.0]}}, tmp_path)
    np.testing.assert_array_equal(scene.colors, red.colors)
    assert scene.colors[0, 0] > scene.colors[0, 1]


def test_specular_glossiness_diffuse_texture(tmp_path):
    material = {"extensions": {"KHR_materials_pbrSpecularGlossiness": {"diffuseTexture": {"index": 0}}}}
    assert _box_with(material, tmp_path, png((4, 4))).textured
    assert not _box_with({}, tmp_path, png((4, 4))).textured


def test_a_webp_only_texture_is_read(tmp_path):
    """EXT_texture_webp with no PNG fallback: the texture's image is the extension's."""
    import io

    from PIL import Image

    blob = io.BytesIO()
    Image.new("RGB", (4, 4), (200, 30, 30)).save(blob, format="WEBP")
    doc_texture = {"extensions": {"EXT_texture_webp": {"source": 0}}}
    material = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}
    scene = _box_with(material, tmp_path, blob.getvalue(), texture=doc_texture)
    assert scene.textured and len(scene.textures) == 1
    assert abs(int(scene.textures[0][..., 0].mean()) - 200) <= 8


def test_nan_in_fields_rtta_does_not_read_is_no_traceback(tmp_path):
    """Python's JSON reader takes NaN; a NaN in a texture's extensions, or a `normalized` that
    is not a boolean, once reached the document rewritten for trimesh and failed there."""
    material = {
        "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0, "extensions": {"X_any": float("nan")}, "texCoord": float("nan")}
        }
    }
    assert _box_with(material, tmp_path, png((4, 4))).textured
    doc, binary = box_doc()
    doc["accessors"][1]["normalized"] = float("nan")
    (tmp_path / "n.glb").write_bytes(glb(doc, binary))
    assert load_scene(tmp_path / "n.glb").count == 1


def test_a_ktx2_only_texture_keeps_the_material_colour_and_says_so(tmp_path):
    """KHR_texture_basisu (KTX2) images cannot be decoded here: the objects keep their base
    colour factor, and a warning names the texture (it was left out silently)."""
    doc_texture = {"extensions": {"KHR_texture_basisu": {"source": 0}}}
    material = {"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.6, 0.9, 1.0], "baseColorTexture": {"index": 0}}}
    ktx2 = b"\xabKTX 20\xbb\r\n\x1a\n" + bytes(64)
    scene = _box_with(material, tmp_path, ktx2, texture=doc_texture)
    plain = _box_with({"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.6, 0.9, 1.0]}}, tmp_path)
    assert not scene.textured
    np.testing.assert_array_equal(scene.colors, plain.colors)
    said = [w for w in scene.warnings if "KHR_texture_basisu" in w]
    assert len(said) == 1 and "texture 0" in said[0] and "material colour" in said[0], scene.warnings
