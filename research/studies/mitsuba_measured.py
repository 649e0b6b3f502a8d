"""A measurement rendered in Mitsuba as it is, against through its MERL table or with the camera first.

    python research/studies/mitsuba_measured.py ../shared/data/rgl-measured/*.bsdf --out research/results/real/mitsuba

For each ``.bsdf``, the plugin's sphere (:func:`frenbrdf.render.mitsuba.render_material`, 128², 1024 spp)
of the measurement as the plugin now evaluates it (Mitsuba's ``measured``, light first) is compared, in
display PSNR, with: the same render under another sampler seed (the Monte Carlo noise floor); the
measurement's MERL table (what the plugin rendered before); and the measurement with the camera's
direction first (Mitsuba's ``measured`` on its own). Writes ``mitsuba.json`` and ``mitsuba.png`` (rows:
the materials; columns: as it is, its table, camera first).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import frenbrdf
from frenbrdf.io.atomic import save_json
from frenbrdf.render import mitsuba as fm

sys.path[:0] = [str(Path(__file__).resolve().parents[2] / "benches")]  # benches/
from common import run_metadata  # noqa: E402


def display_psnr(a: np.ndarray, b: np.ndarray) -> float:
    return float(10 * np.log10(1.0 / np.mean((fm.tonemap(a) - fm.tonemap(b)) ** 2)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="+", type=Path, help="RGL .bsdf measurements")
    parser.add_argument("--out", type=Path, required=True, help="folder for mitsuba.json and mitsuba.png")
    parser.add_argument("--resolution", type=int, default=128)
    parser.add_argument("--spp", type=int, default=1024)
    args = parser.parse_args()
    fm.register()
    args.out.mkdir(parents=True, exist_ok=True)
    rows, images = [], []
    for path in args.files:
        measurement = frenbrdf.read_bsdf(path)
        camera_first = fm.material_from_measurement(measurement)
        camera_first.ordered = False  # the plugin then passes Mitsuba's (si.wi, wo) as they come
        start = time.perf_counter()
        renders = {"as it is": fm.render_material(measurement, spp=args.spp, resolution=args.resolution, seed=0)}
        seconds = time.perf_counter() - start
        renders["another seed"] = fm.render_material(measurement, spp=args.spp, resolution=args.resolution, seed=1)
        renders["its table"] = fm.render_material(measurement.table(), spp=args.spp, resolution=args.resolution,
                                                  seed=1)
        renders["camera first"] = fm.render_material(camera_first, spp=args.spp, resolution=args.resolution, seed=1)
        row = {"material": measurement.name, "seconds": seconds,
               **{f"psnr_vs_{name.replace(' ', '_')}": display_psnr(renders["as it is"], image)
                  for name, image in renders.items() if name != "as it is"}}
        rows.append(row)
        print(row)
        images.append(np.concatenate([fm.tonemap(renders[k]) for k in ("as it is", "its table", "camera first")], 1))
    fm.save_png(args.out / "mitsuba.png", np.concatenate(images, axis=0))
    save_json(args.out / "mitsuba.json", {"run": run_metadata(), "resolution": args.resolution, "spp": args.spp,
                                          "variant": fm.set_variant(), "rows": rows})
    print(f"wrote {args.out}/mitsuba.{{json,png}}")


if __name__ == "__main__":
    main()
