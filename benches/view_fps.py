"""Frames per second and page sizes of ``frenbrdf view`` in a software renderer (docs/usage.md, "See a material").

Builds pages of real materials, opens each in headless Chromium with WebGL2 on SwiftShader (the CPU: what a
laptop without a GPU driver falls back to, and slower than any integrated GPU), and reports per page its size,
the seconds until every light is accumulated, and the frames per second while the key light turns (the fixed
lights cached: what dragging the light costs), at 256² pixels. With ``--screenshots DIR`` it also writes the
docs' screenshots (the two materials and the edit halfway between them).

    OMP_NUM_THREADS=2 python benches/view_fps.py --data ../shared/data --screenshots docs/view
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

from frenbrdf.io.atomic import atomic_path
from frenbrdf.render.viewer import view
from frenbrdf.render.viewer.browser import Browser


def measure(browser: Browser, path: Path, query: str = "", screenshot: Path | None = None) -> dict:
    page = browser.open(path.as_uri() + query, size=(820, 580))
    page.wait("window.frenbrdfView && (window.frenbrdfView.ready || window.frenbrdfView.error)", timeout=300)
    error = page.evaluate("window.frenbrdfView.error")
    if error:
        raise RuntimeError(f"{path}: {error}")
    converge = page.evaluate("window.frenbrdfView.secondsToConverge")
    if screenshot:
        with atomic_path(screenshot) as temporary:  # whole or not at all; the folder made if missing
            temporary.write_bytes(page.screenshot())
    fps = page.evaluate("window.frenbrdfView.measure(30)")
    return {"page": path.name, "query": query, "kib": round(path.stat().st_size / 1024), "converge_s": round(converge, 1),
            "fps_key_light": round(fps, 1), "console_errors": page.console_errors()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", required=True, help="the shared data folder (merl-nbrdf/, rgl-measured/)")
    parser.add_argument("--screenshots", help="folder for the docs' screenshots")
    args = parser.parse_args()
    data = Path(args.data)
    a, b = data / "merl-nbrdf" / "gold-paint.h5", data / "merl-nbrdf" / "blue-metallic-paint.h5"
    shots = Path(args.screenshots) if args.screenshots else None
    rows = []
    with tempfile.TemporaryDirectory() as folder, Browser() as browser:
        folder = Path(folder)
        started = time.perf_counter()
        pages = {"gold-paint.html": view(a), "measured-paper.html": view(data / "rgl-measured" / "paper_blue_rgb.bsdf")}
        built = {"single": time.perf_counter() - started}
        started = time.perf_counter()
        pages["edit.html"] = view(a, b)
        built["edit"] = time.perf_counter() - started
        for name, page in pages.items():
            (folder / name).write_text(page.html, encoding="utf-8")
        rows.append(measure(browser, folder / "gold-paint.html"))
        rows.append(measure(browser, folder / "measured-paper.html"))
        for t, mode, shot in ((0.0, "kept", "gold-paint.png"), (1.0, "kept", "blue-metallic-paint.png"),
                              (0.5, "kept", "halfway.png"), (0.5, "latent", None)):
            rows.append(measure(browser, folder / "edit.html", f"?t={t}&edit={mode}",
                                shots / shot if shots and shot else None))
    print(json.dumps({"build_s": {k: round(v, 1) for k, v in built.items()}, "pages": rows}, indent=2))


if __name__ == "__main__":
    main()
