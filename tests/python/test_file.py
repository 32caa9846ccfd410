"""vff.open and vff.File: the conformance vectors through Python, zero-copy maps, errors."""
import gc
import json
import sys

import numpy as np
import pytest

import vff
from conftest import VECTORS, expected, valid_vectors

SNAKE = {"positionScheme": "position_scheme", "positionParam": "position_param", "mapCount": "map_count",
         "directionScheme": "direction_scheme", "mapResolution": "map_resolution", "frame": "frame",
         "distanceEncoding": "distance_encoding", "missCode": "miss_code", "normalEncoding": "normal_encoding"}
LAYOUT = {"target": "target", "gutter": "gutter", "tileSize": "tile_size", "tilesPerRow": "tiles_per_row",
          "tilesPerColumn": "tiles_per_column", "sliceWidth": "slice_width", "sliceHeight": "slice_height",
          "sliceCount": "slice_count", "maxTextureSize": "max_texture_size", "maxLayers": "max_layers"}


def close(a, b):
    return abs(a - b) <= 2e-6 * max(1.0, abs(b))


def test_vectors_describe_as_expected():
    assert len(valid_vectors()) >= 10
    for path in valid_vectors():
        want = expected(path)
        f = vff.open(str(path))
        assert f.version == (want["versionMajor"], want["versionMinor"]), path.name
        assert f.file_size == want["fileSize"]
        for k, attr in SNAKE.items():
            assert getattr(f, attr) == want["field"][k], (path.name, k)
        assert f.center == pytest.approx(tuple(want["field"]["sphere"]["center"]))
        assert close(f.radius, want["field"]["sphere"]["radius"])
        for k, key in LAYOUT.items():
            assert f.layout[key] == want["layout"][k], (path.name, k)
        assert [s["tag"] for s in f.sections] == [s["tag"] for s in want["sections"]]
        assert [s["codec"] for s in f.sections] == [s["codec"] for s in want["sections"]]
        assert [s["known"] for s in f.sections] == [s["known"] for s in want["sections"]]
        for plane, p in want["planes"].items():
            got = f.describe()["planes"][plane]
            assert got["map_bytes"] == p["mapBytes"] and got["maps_per_block"] == p["mapsPerBlock"]
            assert got["block_codecs"] == p["blockCodecs"]
        assert f.has_normals == ("normal" in want["planes"])


def test_vectors_metadata_as_expected():
    for path in valid_vectors():
        want = expected(path)["metadata"]
        f = vff.open(str(path))
        if want is None:
            assert f.metadata == {} and f.metadata_text == ""
        elif isinstance(want, str):  # stored text that is not canonical: handed out unchanged
            assert f.metadata_text == want, path.name
            assert f.metadata == json.loads(want)
        else:
            assert f.metadata == want, path.name


def test_vectors_decode_to_expected_values():
    checked = 0
    for path in valid_vectors():
        want = expected(path)
        f = vff.open(str(path))
        m = f.map_resolution
        for entry in want["maps"]:
            i = entry["map"]
            d = f.distances(i).reshape(-1)
            for k, w in enumerate(entry["distance"]):
                if w is None:
                    assert np.isnan(d[k]), (path.name, i, k)
                elif f.distance_encoding == "bit1":
                    assert d[k] == w
                else:
                    assert close(float(d[k]), w), (path.name, i, k, float(d[k]), w)
                checked += 1
            if "normals" in entry and f.has_normals:
                n = f.normals(i).reshape(m * m, 3)
                for k, w in enumerate(entry["normals"]):
                    if w is None:
                        assert np.isnan(n[k]).all()
                    else:
                        assert np.allclose(n[k], w, atol=1e-6), (path.name, i, k)
    assert checked > 10000


def test_invalid_vectors_raise_their_id():
    seen = 0
    for expect in sorted((VECTORS / "invalid").glob("*/*.expect.json")):
        want = json.loads(expect.read_text())
        path = expect.with_name(expect.name.replace(".expect.json", ".vff"))
        opened = want["observed"]["open"]["verify-all"]["open"]
        if opened:
            with pytest.raises(vff.Error) as e:
                vff.open(str(path))
            assert e.value.code == opened, path
            if 2000 <= opened < 9000:
                assert isinstance(e.value, vff.InvalidFileError) and e.value.validation_id == opened
        codes = [p["code"] for p in want["observed"]["validate"]]
        if not opened:
            problems = vff.open(str(path), checksums="none").validate()
            assert [p.id for p in problems] == codes, path
            assert [p.offset for p in problems] == [p["offset"] for p in want["observed"]["validate"]]
            assert [p.section for p in problems] == [p["section"] for p in want["observed"]["validate"]]
        seen += 1
    assert seen >= 30


def test_validate_reports_warnings():
    f = vff.open(str(VECTORS / "valid" / "rocompat-bit0.vff"))
    problems = f.validate()
    assert [(p.id, p.name, p.severity) for p in problems] == [(3008, "ro-compat-feature", "warning")]
    assert vff.open(str(VECTORS / "valid" / "u8d-stored.vff")).validate() == []


def test_errors_carry_code_section_offset(tmp_path):
    with pytest.raises(vff.IoError) as e:
        vff.open(str(tmp_path / "none.vff"))
    assert e.value.code == 1001 and e.value.offset is None and isinstance(e.value, OSError)
    bad = tmp_path / "flip.vff"
    data = bytearray((VECTORS / "valid" / "u8d-stored.vff").read_bytes())
    data[56] ^= 1  # headerChecksum
    bad.write_bytes(bytes(data))
    with pytest.raises(vff.InvalidFileError) as e:
        vff.open(str(bad))
    assert (e.value.code, e.value.name, e.value.offset) == (3005, "header-checksum", 56)
    assert "header-checksum (3005)" in str(e.value)
    with pytest.raises(ValueError, match="checksums"):
        vff.open(str(bad), checksums="sometimes")


def test_map_arrays_are_zero_copy_views():
    path = VECTORS / "valid" / "u8d-stored.vff"
    raw = path.read_bytes()
    f = vff.open(str(path))
    a = f.map(3)
    assert a.shape == (8, 8) and a.dtype == np.uint8 and not a.flags.writeable
    # The same memory as the file's mapping: two views of one map share it, and its bytes are the file's.
    b = f.map(3)
    assert np.shares_memory(a, b)
    start = raw.find(a.tobytes())
    assert start > 0 and start % 64 == 0
    all_maps = f.maps()
    assert all_maps.shape == (f.map_count, 8, 8) and np.shares_memory(all_maps, a)
    assert np.array_equal(all_maps[3], a)
    with pytest.raises(ValueError):
        a[0, 0] = 1
    u16 = vff.open(str(VECTORS / "valid" / "u16d-stored-meta-slices.vff")).map(0)
    assert u16.dtype == np.dtype("<u2") and u16.shape == (8, 8)
    normals = vff.open(str(VECTORS / "valid" / "u8c-stored-normals-3d-gutter1.vff")).map(1, "normal")
    assert normals.dtype == np.dtype("<i2") and normals.shape == (8, 8, 2)
    with pytest.raises(IndexError):
        f.map(f.map_count)


def test_arrays_keep_the_file_alive():
    f = vff.open(str(VECTORS / "valid" / "u8d-zstd-normals-meta.vff"))
    a = f.map(5)
    n = f.map(5, "normal")
    want_a, want_n = a.copy(), n.copy()
    refs = sys.getrefcount(f)
    assert a.base is f or a.base is not None
    del f
    gc.collect()
    # The File lives on as the arrays' base: the memory is still the field's.
    assert isinstance(a.base, vff.File) and isinstance(n.base, vff.File)
    assert np.array_equal(a, want_a) and np.array_equal(n, want_n)
    assert refs >= 2


def test_inspect_and_slices():
    d = vff.inspect(str(VECTORS / "valid" / "u16d-stored-meta-slices.vff"))
    assert d["field"]["map_count"] == 7 and d["layout"]["slice_count"] == 2 and d["problems"] == []
    f = vff.open(str(VECTORS / "valid" / "u16d-stored-meta-slices.vff"))
    s = f.slice(1)
    assert s.dtype == np.uint8 and s.size == f.layout["slice_width"] * f.layout["slice_height"] * 2
    with pytest.raises(IndexError):
        f.slice(2)
    assert vff.__version__.count(".") == 2 and vff.format_version[0] == 1
