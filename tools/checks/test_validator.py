"""glTF files written by `pgvol remesh` pass the Khronos glTF validator."""

from __future__ import annotations

import json
import shutil

import pytest

import helpers
from helpers import REMESH_MESHES


@pytest.fixture(scope="session")
def validator(repo_root):
    node = shutil.which("node")
    if node is None:
        pytest.fail("node is not on PATH; the glTF validator needs Node.js")
    if not (repo_root / "tools" / "node_modules" / "gltf-validator").is_dir():
        pytest.fail("gltf-validator is not installed: run `npm ci --prefix tools` (tools/test.sh does this)")

    def _validate(path):
        r = helpers.run([node, helpers.VALIDATOR, path], timeout=300)
        lines = [line for line in r.stdout.splitlines() if line.strip()]
        if len(lines) != 1:
            pytest.fail("unexpected validator output\n" + r.describe())
        summary = json.loads(lines[0])
        return r.returncode, summary

    return _validate


def _assert_valid(validator, path):
    code, summary = validator(path)
    assert code == 0 and summary["ok"] and summary["numErrors"] == 0, (
        f"{path.name}: {summary.get('numErrors')} validation error(s): "
        + json.dumps(summary.get("errors") or summary.get("fatal"), indent=1)
    )


@pytest.mark.parametrize("name", REMESH_MESHES)
def test_remeshed_glb_is_valid(name, remesh, validator):
    _assert_valid(validator, remesh(name, ".glb"))


def test_remeshed_gltf_is_valid(remesh, validator):
    out = remesh("spot", ".gltf", res=32)
    _assert_valid(validator, out)
    # The separate-file form must still load as a mesh.
    assert len(helpers.load_output(out).faces) > 0
