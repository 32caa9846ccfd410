"""The glTF extension's sample assets (spec/conformance/gltf/, spec/gltf/VFF_visibility_field) in the
Python module: vff.read_gltf_fields reports every asset's problems (rule, name, severity, JSON
pointer, in check order) and fields (match, usability, hashes, payload, nodes) as manifest.json
lists them. One test per asset, so that each is its own ctest case; test_every_asset_has_a_test
fails when an asset is added without one. A usable field opens as a vff.File; the others refuse."""
import base64
import json
import re
import struct

import pytest

import vff
from conftest import VECTORS

GLTF = VECTORS / "gltf"


def manifest():
    return json.loads((GLTF / "manifest.json").read_text())


def case_name(asset):
    return "test_" + re.sub(r"[^a-z0-9]", "_", asset.lower())


def gltf_json_and_bin(path):
    """The asset's JSON and its GLB binary chunk (None for a .gltf), read here, not by the module."""
    data = path.read_bytes()
    if data[:4] != b"glTF":
        return json.loads(data), None
    json_length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20:20 + json_length])
    at = 20 + json_length
    binary = None
    if at + 8 <= len(data):
        length, kind = struct.unpack_from("<II", data, at)
        if kind == 0x004E4942:
            binary = data[at + 8:at + 8 + length]
    return doc, binary


def payload(path, field):
    """The payload the extension names, read here: the bufferView's bytes, a data: URI or a file."""
    doc, binary = gltf_json_and_bin(path)
    ext = doc["meshes"][field.mesh]["extensions"]["VFF_visibility_field"]
    if "bufferView" in ext:
        view = doc["bufferViews"][ext["bufferView"]]
        offset = view.get("byteOffset", 0)
        return binary[offset:offset + view["byteLength"]]
    uri = ext["uri"]
    if uri.startswith("data:"):
        return base64.b64decode(uri.split(",", 1)[1])
    return (path.parent / uri).read_bytes()


def check(asset):
    want = manifest()["assets"][asset]
    path = GLTF / asset
    r = vff.read_gltf_fields(str(path))
    got = [(p["rule"], p["name"], p["severity"], p["path"]) for p in r.problems]
    assert got == [(p["rule"], p["name"], p["severity"], p["path"]) for p in want["problems"]], r.problems
    for p, w in zip(r.problems, want["problems"]):
        assert p["message"], p
        if "vffCodes" in w:  # a payload libvff refuses: the message names one of its validator's codes
            assert any(" (%d)" % c in p["message"] for c in w["vffCodes"]), (p["message"], w["vffCodes"])
    assert r.has_error == want["hasError"]
    if "meshes" in want:
        assert r.mesh_count == want["meshes"]
    assert len(r.fields) == len(want["fields"])
    for f, w in zip(r.fields, want["fields"]):
        assert f.mesh == w["mesh"]
        assert f.path == "/meshes/%d/extensions/VFF_visibility_field" % f.mesh
        assert (f.valid, f.usable, f.match) == (w["valid"], w["usable"], w["match"])
        if not w["valid"]:
            assert f.bytes == b""
            # open() refuses it with its mesh's error
            mesh = "/meshes/%d" % f.mesh
            rules = [p["rule"] for p in want["problems"] if p["path"] == mesh or p["path"].startswith(mesh + "/")]
            with pytest.raises(vff.GltfError) as e:
                f.open()
            assert e.value.code == rules[0]
            continue
        assert f.name == w["name"]
        assert f.geometry_hash == w["geometryHash"]
        assert f.mesh_geometry_hash == w["meshGeometryHash"]
        assert len(f.bytes) == w["bytes"]
        assert f.bytes == payload(path, f)
        if w["source"] == "bufferView":
            assert f.buffer_view is not None and f.buffer_view >= 0 and f.uri is None
        else:
            assert f.buffer_view is None and f.uri
        if "tolerance" in w:
            assert f.tolerance == pytest.approx(w["tolerance"], abs=1e-15)
            assert f.bounds_difference == pytest.approx(w["boundsDifference"], abs=1e-15)
        assert [(n["node"], n["answered"]) for n in f.nodes] == [(n["node"], n["answered"]) for n in w["nodes"]]
        if f.usable:
            field = f.open()
            assert field.map_count > 0
        else:  # a mismatch: the field may not answer for its mesh
            with pytest.raises(vff.GltfError) as e:
                f.open()
            assert e.value.code == 14103


def test_every_asset_has_a_test():
    assets = manifest()["assets"]
    on_disk = sorted(str(p.relative_to(GLTF)) for p in GLTF.glob("*/*.gl*") if p.suffix in (".glb", ".gltf"))
    assert sorted(assets) == on_disk
    assert len(assets) >= 50
    missing = [a for a in assets if case_name(a) not in globals()]
    assert not missing, "add a test_* function for each: %s" % missing


# One test per asset (manifest.json).

def test_invalid_14001_asset_version_before_required_gltf():
    check("invalid/14001-asset-version-before-required.gltf")


def test_invalid_14001_asset_version_gltf():
    check("invalid/14001-asset-version.gltf")


def test_invalid_14001_glb_length_glb():
    check("invalid/14001-glb-length.glb")


def test_invalid_14001_glb_magic_glb():
    check("invalid/14001-glb-magic.glb")


def test_invalid_14001_json_syntax_gltf():
    check("invalid/14001-json-syntax.gltf")


def test_invalid_14002_extension_required_glb():
    check("invalid/14002-extension-required.glb")


def test_invalid_14003_extension_not_used_glb():
    check("invalid/14003-extension-not-used.glb")


def test_invalid_14003_not_used_before_extension_value_glb():
    check("invalid/14003-not-used-before-extension-value.glb")


def test_invalid_14004_buffer_view_negative_glb():
    check("invalid/14004-buffer-view-negative.glb")


def test_invalid_14004_buffer_view_type_glb():
    check("invalid/14004-buffer-view-type.glb")


def test_invalid_14004_extension_value_before_buffer_view_glb():
    check("invalid/14004-extension-value-before-buffer-view.glb")


def test_invalid_14004_geometry_hash_length_glb():
    check("invalid/14004-geometry-hash-length.glb")


def test_invalid_14004_geometry_hash_missing_glb():
    check("invalid/14004-geometry-hash-missing.glb")


def test_invalid_14004_geometry_hash_type_glb():
    check("invalid/14004-geometry-hash-type.glb")


def test_invalid_14004_geometry_hash_uppercase_glb():
    check("invalid/14004-geometry-hash-uppercase.glb")


def test_invalid_14004_max_missing_glb():
    check("invalid/14004-max-missing.glb")


def test_invalid_14004_max_not_a_number_glb():
    check("invalid/14004-max-not-a-number.glb")


def test_invalid_14004_mime_type_type_glb():
    check("invalid/14004-mime-type-type.glb")


def test_invalid_14004_min_above_max_glb():
    check("invalid/14004-min-above-max.glb")


def test_invalid_14004_min_two_numbers_glb():
    check("invalid/14004-min-two-numbers.glb")


def test_invalid_14004_min_type_glb():
    check("invalid/14004-min-type.glb")


def test_invalid_14004_not_an_object_glb():
    check("invalid/14004-not-an-object.glb")


def test_invalid_14004_uri_type_glb():
    check("invalid/14004-uri-type.glb")


def test_invalid_14005_both_sources_glb():
    check("invalid/14005-both-sources.glb")


def test_invalid_14005_no_source_glb():
    check("invalid/14005-no-source.glb")


def test_invalid_14006_buffer_uri_missing_gltf():
    check("invalid/14006-buffer-uri-missing.gltf")


def test_invalid_14006_buffer_view_index_glb():
    check("invalid/14006-buffer-view-index.glb")


def test_invalid_14006_buffer_view_out_of_range_glb():
    check("invalid/14006-buffer-view-out-of-range.glb")


def test_invalid_14006_buffer_view_stride_glb():
    check("invalid/14006-buffer-view-stride.glb")


def test_invalid_14006_first_mesh_second_valid_gltf():
    check("invalid/14006-first-mesh-second-valid.gltf")


def test_invalid_14006_no_binary_chunk_glb():
    check("invalid/14006-no-binary-chunk.glb")


def test_invalid_14007_data_uri_not_base64_gltf():
    check("invalid/14007-data-uri-not-base64.gltf")


def test_invalid_14007_uri_absolute_path_gltf():
    check("invalid/14007-uri-absolute-path.gltf")


def test_invalid_14007_uri_backslash_gltf():
    check("invalid/14007-uri-backslash.gltf")


def test_invalid_14007_uri_bad_percent_gltf():
    check("invalid/14007-uri-bad-percent.gltf")


def test_invalid_14007_uri_decoded_nul_gltf():
    check("invalid/14007-uri-decoded-nul.gltf")


def test_invalid_14007_uri_missing_file_gltf():
    check("invalid/14007-uri-missing-file.gltf")


def test_invalid_14007_uri_network_path_gltf():
    check("invalid/14007-uri-network-path.gltf")


def test_invalid_14007_uri_query_gltf():
    check("invalid/14007-uri-query.gltf")


def test_invalid_14007_uri_scheme_gltf():
    check("invalid/14007-uri-scheme.gltf")


def test_invalid_14008_mime_type_missing_glb():
    check("invalid/14008-mime-type-missing.glb")


def test_invalid_14008_mime_type_wrong_glb():
    check("invalid/14008-mime-type-wrong.glb")


def test_invalid_14009_payload_checksum_glb():
    check("invalid/14009-payload-checksum.glb")


def test_invalid_14009_payload_magic_glb():
    check("invalid/14009-payload-magic.glb")


def test_invalid_14009_payload_partial_glb():
    check("invalid/14009-payload-partial.glb")


def test_invalid_14010_hash_conflict_gltf():
    check("invalid/14010-hash-conflict.gltf")


def test_invalid_14011_mesh_lines_only_gltf():
    check("invalid/14011-mesh-lines-only.gltf")


def test_valid_close_glb():
    check("valid/close.glb")


def test_valid_data_uri_gltf():
    check("valid/data-uri.gltf")


def test_valid_external_uri_gltf():
    check("valid/external-uri.gltf")


def test_valid_meta_without_geometry_hash_glb():
    check("valid/meta-without-geometry-hash.glb")


def test_valid_mismatch_glb():
    check("valid/mismatch.glb")


def test_valid_one_mesh_glb():
    check("valid/one-mesh.glb")


def test_valid_two_meshes_three_nodes_glb():
    check("valid/two-meshes-three-nodes.glb")


def test_valid_used_without_field_glb():
    check("valid/used-without-field.glb")
