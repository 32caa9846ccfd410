"""Partial results (spec/partial.md) in the Python module: vff.File.partial gives the range of every
valid partial result of the conformance vectors (spec/conformance/partial/manifest.json), None for a
whole field; a query refuses a partial result as FieldQuery::fromFile does."""
import json

import pytest

import vff
from conftest import VECTORS

PARTIAL = VECTORS / "partial"


def manifest():
    return json.loads((PARTIAL / "manifest.json").read_text())


def valid_partials():
    return sorted(manifest()["partials"].items())


def test_every_valid_partial_reports_its_range():
    partials = valid_partials()
    # every part of every valid set (a folder not named by a rule ID) is listed
    on_disk = sorted(str(p.relative_to(PARTIAL)) for p in (PARTIAL / "merge").glob("*/p*.vff")
                     if not p.parent.name[0].isdigit())
    assert [name for name, _ in partials] == on_disk
    assert len(partials) >= 6
    for name, r in partials:
        f = vff.open(str(PARTIAL / name))
        assert f.partial == (r["mapBegin"], r["mapEnd"]), name
        assert f.map_count == r["mapCount"], name
        assert f.metadata["vff.partial"]["mapBegin"] == r["mapBegin"]


def test_whole_fields_are_not_partial():
    expected = sorted((PARTIAL / "merge").glob("*/expected.vff"))
    assert len(expected) >= 3
    for path in expected:
        assert vff.open(str(path)).partial is None, path


def test_a_partial_without_a_valid_range_is_still_partial():
    # 12009: mapEnd 7 of 6 maps; 12003: "vff.partial" is a string
    assert vff.open(str(PARTIAL / "merge/12009-partial-range/p2.vff")).partial == (None, None)
    assert vff.open(str(PARTIAL / "merge/12003-partial-object/p2.vff")).partial == (None, None)
    assert vff.open(str(PARTIAL / "merge/12002-partial-missing/p2.vff")).partial is None


def test_queries_refuse_a_partial_result():
    name, r = valid_partials()[0]
    f = vff.open(str(PARTIAL / name))
    with pytest.raises(vff.UnsupportedError) as e:
        vff.FieldQuery(f)
    assert e.value.code == 9005 and e.value.name == "unsupported"
    assert "partial result" in str(e.value)
    # the merged whole field answers
    whole = vff.open(str(PARTIAL / "merge/stored-two-parts/expected.vff"))
    assert vff.FieldQuery(whole) is not None
