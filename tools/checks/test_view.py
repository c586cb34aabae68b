"""`pgvol view` checked in headless Chromium: the page opens to ready with the surface drawn,
a section at mid height reports the area `pgvol slice` gives, nothing is loaded from the
network, and bad input writes nothing. The script bundle the binary includes rebuilds byte for
byte from tools/viewer's lock file."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import chromium
import helpers

pytestmark = pytest.mark.skipif(
    chromium.chromium_path() is None, reason="chromium is missing (tools/test.sh installs it with apt)"
)


# Rows of a screenshot the control panel covers.
PANEL_ROWS = 140


@pytest.fixture(scope="module")
def spot_pgv(pgvol, mesh_path, work_dir) -> Path:
    out = work_dir / "view-spot-128.pgv"
    if not out.exists():
        helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", out, "--res", 128])
    return out


@pytest.fixture(scope="module")
def spot_page(pgvol, spot_pgv, work_dir) -> Path:
    page = work_dir / "view-spot.html"
    helpers.run_ok([pgvol, "view", spot_pgv, "-o", page, "--quiet"])
    return page


def _mid_height(pgvol, pgv: Path) -> float:
    info = helpers.run_json([pgvol, "info", pgv, "--json"])
    lo, hi = info["header"]["source_bounds"]
    return round((lo[2] + hi[2]) / 2, 6)


def test_the_page_opens_to_ready_with_the_surface(spot_page):
    state = chromium.page_state(spot_page)
    assert state.get("status") == "ready", state
    assert int(state["triangles"]) > 1000, state
    assert "section-area" not in state, "no section was asked for"


def test_the_screenshot_shows_a_lit_surface(spot_page, work_dir):
    from PIL import Image

    png = chromium.screenshot(spot_page, work_dir / "view-spot.png")
    # Below the control panel (top left, about 130 px high): the 3D view alone.
    pixels = np.asarray(Image.open(png).convert("RGB")).astype(np.int32)[PANEL_ROWS:]
    background = np.array([255, 255, 255])
    drawn = np.any(np.abs(pixels - background) > 8, axis=2)
    assert drawn.mean() >= 0.05, f"only {drawn.mean():.1%} of the pixels are drawn"
    grey = (pixels[..., 0] * 299 + pixels[..., 1] * 587 + pixels[..., 2] * 114) // 1000
    levels = len(np.unique(grey[drawn]))
    assert levels >= 20, f"the drawn pixels take only {levels} grey levels: not a lit surface"


def test_a_section_at_mid_height_has_the_area_pgvol_slice_gives(pgvol, spot_pgv, spot_page, work_dir):
    height = _mid_height(pgvol, spot_pgv)
    layers = work_dir / "view-spot-mid.json"
    helpers.run_ok([pgvol, "slice", spot_pgv, "-o", layers, "--layer-height", 1.0, "--first", height])
    reference = json.loads(layers.read_text())["layers"][0]
    assert abs(reference["height"] - height) < 1e-6, reference["height"]
    state = chromium.page_state(spot_page, f"section=z:{height}")
    assert state.get("status") == "ready", state
    assert state["section-axis"] == "z"
    assert abs(float(state["section-height"]) - height) < 1e-6, state
    area = float(state["section-area"])
    assert reference["area"] > 0
    assert abs(area - reference["area"]) <= 0.02 * reference["area"], (area, reference["area"])


def test_the_section_written_in_is_shown_and_the_address_overrides_it(pgvol, spot_pgv, work_dir):
    page = work_dir / "view-spot-section.html"
    helpers.run_ok([pgvol, "view", spot_pgv, "-o", page, "--section", "y:0.1", "--quiet"])
    written = chromium.page_state(page)
    assert (written.get("status"), written.get("section-axis")) == ("ready", "y"), written
    assert float(written["section-area"]) > 0
    moved = chromium.page_state(page, "section=x:0.0")
    assert moved.get("section-axis") == "x", moved
    assert float(moved["section-area"]) != float(written["section-area"])


def test_an_address_outside_the_field_says_so_and_keeps_the_surface(spot_page, work_dir):
    dom = chromium.dump_dom(spot_page, "section=z:50")
    state = chromium.body_state(dom)
    assert (state.get("status"), state.get("section-axis")) == ("ready", "z"), state
    assert float(state["section-area"]) == 0.0
    assert "is outside the field" in dom
    # The surface is not cut away: the view below the panel is drawn as without a section.
    from PIL import Image

    png = chromium.screenshot(spot_page, work_dir / "view-spot-outside.png", "section=z:50")
    pixels = np.asarray(Image.open(png).convert("RGB")).astype(np.int32)[PANEL_ROWS:]
    drawn = np.any(np.abs(pixels - np.array([255, 255, 255])) > 8, axis=2)
    assert drawn.mean() >= 0.05, f"only {drawn.mean():.1%} of the pixels are drawn"


def test_the_page_loads_nothing_from_the_network(spot_page):
    text = spot_page.read_text()
    # Elements and calls that load: none in the page (case-sensitive, as CSS and script spell
    # them; three.js's getDataURL is not one).
    for pattern in [r"<script[^>]*\bsrc\s*=", r"<link\b", r"<img\b", r"<iframe\b", r"\burl\(", r"@import",
                    r"\bfetch\(", r"XMLHttpRequest", r"WebSocket\(", r"\bimport\("]:
        assert not re.search(pattern, text), f"the page holds {pattern!r}"
    # Offline (no name resolves, no proxy answers) it still opens to ready.
    state = chromium.page_state(spot_page, offline=True)
    assert state.get("status") == "ready", state


def test_a_large_grid_is_resampled_onto_the_cap(pgvol, mesh_path, work_dir):
    pgv = work_dir / "view-spot-160.pgv"
    helpers.run_ok([pgvol, "encode", mesh_path("spot"), "-o", pgv, "--res", 160])
    page = work_dir / "view-spot-capped.html"
    helpers.run_ok([pgvol, "view", pgv, "-o", page, "--max-res", 96, "--quiet"])
    data = json.loads(re.search(r'id="pgvol-data">(.*?)</script>', page.read_text(), re.S).group(1))
    assert data["field"]["source"] == "samples" and max(data["field"]["dims"]) == 96
    assert max(data["surface"]["grid"]) == 96
    height = _mid_height(pgvol, pgv)
    layers = work_dir / "view-spot-160-mid.json"
    helpers.run_ok([pgvol, "slice", pgv, "-o", layers, "--layer-height", 1.0, "--first", height])
    reference = json.loads(layers.read_text())["layers"][0]["area"]
    state = chromium.page_state(page, f"section=z:{height}")
    assert state.get("status") == "ready", state
    # Linear interpolation of samples 1.7 times coarser: a looser bound than the stored grid's.
    assert abs(float(state["section-area"]) - reference) <= 0.05 * reference


def test_a_mesh_far_from_the_origin_is_viewed_with_its_own_heights(pgvol, mesh_path, work_dir):
    # Spot moved 1e5 along x and z: the page works in the field's local frame and shows world
    # heights, and its section matches pgvol slice's there.
    far = work_dir / "view-spot-far.obj"
    lines = []
    for line in mesh_path("spot").read_text().splitlines():
        if line.startswith("v "):
            x, y, z = map(float, line.split()[1:4])
            line = f"v {x + 1e5:.6f} {y:.6f} {z + 1e5:.6f}"
        lines.append(line)
    far.write_text("\n".join(lines) + "\n")
    page = work_dir / "view-spot-far.html"
    # A mesh input: encoded first (at 128 nodes per axis by default).
    helpers.run_ok([pgvol, "view", far, "-o", page, "--quiet"])
    height = 100000.1
    layers = work_dir / "view-spot-far.json"
    helpers.run_ok([pgvol, "slice", far, "-o", layers, "--layer-height", 1.0, "--first", height, "--res", 128])
    reference = json.loads(layers.read_text())["layers"][0]["area"]
    state = chromium.page_state(page, f"section=z:{height}")
    assert state.get("status") == "ready" and int(state["triangles"]) > 1000, state
    assert abs(float(state["section-height"]) - height) < 1e-6
    assert abs(float(state["section-area"]) - reference) <= 0.02 * reference, (state, reference)


@pytest.mark.parametrize(
    "case",
    ["missing", "not-a-mesh", "bad-pgv", "bad-section", "bad-colour", "outside-section", "not-html"],
)
def test_bad_input_is_refused_and_nothing_is_written(pgvol, spot_pgv, tmp_path, case):
    out = tmp_path / "view.html"
    args = [spot_pgv]
    expect = ""
    if case == "missing":
        args, expect = [tmp_path / "nowhere.pgv"], "nowhere.pgv"
    elif case == "not-a-mesh":
        bad = tmp_path / "notes.txt"
        bad.write_text("hello\n")
        args, expect = [bad], "notes.txt"
    elif case == "bad-pgv":
        bad = tmp_path / "broken.pgv"
        bad.write_bytes(b"PGV\x00" + b"\x01" * 40)
        args, expect = [bad], "broken.pgv"
    elif case == "bad-section":
        args, expect = [spot_pgv, "--section", "w:1"], "AXIS:HEIGHT"
    elif case == "bad-colour":
        args, expect = [spot_pgv, "--color", "surface=red"], "#rrggbb"
    elif case == "outside-section":
        args, expect = [spot_pgv, "--section", "z:50"], "outside the field"
    elif case == "not-html":
        out, expect = tmp_path / "view.png", ".html"
    result = helpers.run([pgvol, "view", *args, "-o", out])
    assert result.returncode != 0, result.describe()
    assert "panicked" not in result.stderr, result.describe()
    assert expect in result.stderr, result.describe()
    assert list(tmp_path.glob("*.htm*")) == [] and not out.exists(), list(tmp_path.iterdir())


def test_the_committed_bundle_rebuilds_from_the_lock_file(repo_root, tmp_path):
    npm = shutil.which("npm")
    if npm is None:
        pytest.skip("npm is missing (tools/test.sh installs the viewer's packages with npm ci)")
    viewer = repo_root / "tools" / "viewer"
    work = tmp_path / "viewer"
    work.mkdir()
    for name in ["package.json", "package-lock.json", "build.mjs"]:
        shutil.copy(viewer / name, work / name)
    shutil.copytree(viewer / "src", work / "src")
    subprocess.run([npm, "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=work, check=True,
                   capture_output=True, timeout=600)
    built = tmp_path / "viewer.min.js"
    subprocess.run(["node", "build.mjs", str(built)], cwd=work, check=True, capture_output=True, timeout=300)
    committed = repo_root / "crates" / "pgvol" / "src" / "view" / "viewer.min.js"
    assert built.read_bytes() == committed.read_bytes(), (
        "the committed bundle differs from a build of tools/viewer; run `node build.mjs` there"
    )
