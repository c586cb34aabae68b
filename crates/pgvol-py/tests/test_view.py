"""`Field.view` writes the page `pgvol view` writes, byte for byte, and `_repr_html_` holds the
same page; in headless Chromium (when installed) the page's section has the area of the
field's own slice."""

from __future__ import annotations

import html
import re
import sys

import numpy as np
import pytest

import pgvol
from conftest import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "tools" / "checks"))
import chromium  # noqa: E402


def _mid_height(field: pgvol.Field) -> float:
    lo, hi = field.bounds
    return round((lo[2] + hi[2]) / 2, 6)


def test_the_page_is_the_one_the_command_line_writes(spot_field, run_cli, tmp_path):
    pgv = tmp_path / "spot.pgv"
    spot_field.save(pgv)
    field = pgvol.Field.load(pgv)
    height = _mid_height(field)
    mine = tmp_path / "python.html"
    field.view(mine, section=("z", height), colours={"section": "#2060c0"}, title="spot")
    theirs = tmp_path / "cli.html"
    run_cli("view", pgv, "-o", theirs, "--section", f"z:{height}", "--color", "section=#2060c0",
            "--title", "spot", "-q")
    assert mine.read_bytes() == theirs.read_bytes()
    text = mine.read_text()
    assert 'data-status="loading"' in text and '"section":"#2060c0"' in text


def test_a_notebook_shows_the_page_in_an_iframe(spot_field, tmp_path):
    shown = spot_field._repr_html_()
    match = re.fullmatch(r'<iframe srcdoc="([^"]*)"[^>]*></iframe>', shown)
    assert match, shown[:200]
    page = tmp_path / "page.html"
    spot_field.view(page)
    assert html.unescape(match.group(1)) == page.read_text()


def test_bad_options_are_refused_and_nothing_is_written(spot_field, tmp_path):
    page = tmp_path / "page.html"
    with pytest.raises(pgvol.ParameterError, match="colour"):
        spot_field.view(page, colours={"surface": "red"})
    with pytest.raises(pgvol.ParameterError, match="colours are"):
        spot_field.view(page, colours={"edges": "#000000"})
    with pytest.raises(pgvol.ParameterError, match="outside the field"):
        spot_field.view(page, section=("z", 40.0))
    with pytest.raises(pgvol.ParameterError, match="resolution cap"):
        spot_field.view(page, max_res=2)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(chromium.chromium_path() is None, reason="chromium is missing")
def test_the_section_in_the_browser_has_the_area_of_the_fields_slice(spot_field, tmp_path):
    height = _mid_height(spot_field)
    page = tmp_path / "page.html"
    spot_field.view(page, section=("z", height))
    state = chromium.page_state(page)
    assert state.get("status") == "ready", state
    layer = spot_field.slice(10.0, first=height)[0]
    # Outer loops counter-clockwise, holes clockwise: the signed areas add up to the section's.
    area = sum(0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))
               for p in (loop.astype(np.float64) for loop in layer.loops))
    assert area > 0
    assert abs(float(state["section-area"]) - area) <= 0.02 * area, (state["section-area"], area)


def test_the_default_cap_is_the_command_lines(spot_field, run_cli, tmp_path):
    import inspect

    default = inspect.signature(pgvol.Field.view).parameters["max_res"].default
    cli_help = run_cli("view", "--help").stdout
    match = re.search(r"--max-res <MAX_RES>.*?\[default: (\d+)\]", cli_help, re.S)
    assert match and int(match.group(1)) == default
    # Spot's 96³ grid under a cap of 64 is resampled: the page's surface grid shows the cap.
    page = tmp_path / "capped.html"
    spot_field.view(page, max_res=64)
    assert '"grid":[64,64,64]' in page.read_text()
