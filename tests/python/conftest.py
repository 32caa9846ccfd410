"""Shared fixtures of the vff module's tests (run by ctest -L python; see CMakeLists.txt)."""
import json
import os
import pathlib
import subprocess

import pytest

try:
    import numpy as np
    import vff
except ImportError as e:  # the module is not built or not on PYTHONPATH
    pytest.skip("SKIP: cannot import vff (%s): build the vff_python target and set PYTHONPATH=build/python" % e,
                allow_module_level=True)

VECTORS = pathlib.Path(os.environ.get("VFF_VECTORS", pathlib.Path(__file__).parents[2] / "spec" / "conformance"))


@pytest.fixture
def vectors():
    return VECTORS


def valid_vectors():
    return sorted((VECTORS / "valid").glob("*.vff"))


def expected(path):
    return json.loads(path.with_name(path.name[:-4] + ".expected.json").read_text())


def rays_around(center, radius, n, seed):
    """n rays about a sphere: a third from inside, the rest aimed at it from outside."""
    rng = np.random.default_rng(seed)
    c = np.asarray(center, np.float32)
    o = (c + rng.uniform(-2.5, 2.5, (n, 3)) * radius).astype(np.float32)
    target = c + rng.uniform(-0.6, 0.6, (n, 3)) * radius
    d = (target - o).astype(np.float32)
    inside = np.arange(n) % 3 == 0
    o[inside] = (c + rng.uniform(-0.5, 0.5, (inside.sum(), 3)) * radius).astype(np.float32)
    d[inside] = rng.uniform(-1, 1, (inside.sum(), 3)).astype(np.float32)
    return o, d


def vff_query(*args, stdin=None):
    """Runs vff-query; returns (exit code, stdout bytes, stderr text)."""
    exe = os.environ.get("VFF_QUERY")
    if not exe:
        pytest.skip("SKIP: VFF_QUERY is not set (run through ctest)")
    r = subprocess.run([exe, *map(str, args)], input=stdin, capture_output=True)
    return r.returncode, r.stdout, r.stderr.decode()
