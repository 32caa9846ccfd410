"""samples/python/ao.py runs and writes its images (small settings; skips without the bunny)."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_ao_sample_writes_images(tmp_path):
    mesh = pathlib.Path(os.environ.get("VFF_MESHES", ROOT.parent / "shared" / "meshes")) / "stanford-bunny.obj"
    if not mesh.exists():
        pytest.skip("SKIP: %s is absent (the test meshes live in ../shared/meshes)" % mesh)
    pytest.importorskip("matplotlib", reason="SKIP: python3-matplotlib is not installed")
    r = subprocess.run([sys.executable, str(ROOT / "samples" / "python" / "ao.py"), "--mesh", str(mesh), "--out",
                        str(tmp_path), "--size", "24", "--rays", "8", "--count", "8", "--map-size", "32"],
                       capture_output=True, text=True, env=os.environ)
    assert r.returncode == 0, r.stderr
    for name in ("ao.png", "ao-error.png", "field.vff"):
        data = (tmp_path / name).read_bytes()
        assert len(data) > 1000, name
    assert (tmp_path / "ao.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rms = {m.group(1): float(m.group(2)) for m in re.finditer(r"^(nearest|interpolated) .*RMS ([0-9.]+)", r.stdout, re.M)}
    assert set(rms) == {"nearest", "interpolated"}, r.stdout
    # A coarse field (290 maps of 32x32) still lands within a few 8-bit levels of the exact image.
    assert rms["nearest"] < 20 and rms["interpolated"] < 20, rms
