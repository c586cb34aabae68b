"""Makes the README's picture of `pgvol view`: spot encoded at 128³, its page written with a
section across the body, screenshotted in headless Chromium (tools/checks/chromium.py, the
helper the checks use).

Usage: python tools/view_screenshot.py [--bin target/release/pgvol] [--out docs/images/view.png]
Needs Debian's chromium and the shared meshes (../shared/meshes or PGVOL_SHARED_MESHES).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools" / "checks"))
import chromium  # noqa: E402
import helpers  # noqa: E402

# A level cut through spot's body (y is up): the filled inside seen from above.
SECTION = "y:0.0"
WINDOW = (960, 600)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin", type=Path, default=helpers.PGVOL_BIN, help="the pgvol binary")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "images" / "view.png", help="the PNG to write")
    args = ap.parse_args(argv)
    mesh = helpers.shared_meshes_dir() / "spot.obj"
    with tempfile.TemporaryDirectory() as work:
        pgv, page = Path(work) / "spot.pgv", Path(work) / "spot.html"
        subprocess.run([str(args.bin), "encode", str(mesh), "-o", str(pgv), "--res", "128", "-q"], check=True)
        subprocess.run([str(args.bin), "view", str(pgv), "-o", str(page), "--section", SECTION,
                        "--title", "spot.pgv (128³)", "-q"], check=True)
        state = chromium.page_state(page, window=WINDOW)
        if state.get("status") != "ready":
            raise SystemExit(f"the page did not open: {state}")
        chromium.screenshot(page, args.out, window=WINDOW)
    print(f"{args.out}: section {SECTION}, area {float(state['section-area']):.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
