import json, sys, numpy as np
from scipy import stats
rows = json.load(open(sys.argv[1]))
powers = list(next(iter(rows.values())).keys())
base = powers[0]
for p in powers:
    ps = np.array([[d["psnr"] for d in r[p]] for r in rows.values()]); de = np.array([[d["delta_e"] for d in r[p]] for r in rows.values()])
    s = np.mean([[d["s"] for d in r[p]] for r in rows.values()])
    b = np.array([[d["psnr"] for d in r[base]] for r in rows.values()]); bde = np.array([[d["delta_e"] for d in r[base]] for r in rows.values()])
    dp = (ps - b).ravel(); dd = (de - bde).ravel()
    def ci(x):
        if np.allclose(x, 0): return (0, 0)
        h = stats.t.ppf(0.975, len(x)-1) * x.std(ddof=1) / np.sqrt(len(x)); return (x.mean()-h, x.mean()+h)
    print(f"p={p}: PSNR {ps.mean():.2f} dE {de.mean():.3f} s {s:.2f} | dPSNR {dp.mean():+.2f} [{ci(dp)[0]:+.2f},{ci(dp)[1]:+.2f}] dDE {dd.mean():+.3f} [{ci(dd)[0]:+.3f},{ci(dd)[1]:+.3f}]",
          " per material:", {k: round(float(np.mean([d['psnr'] for d in r[p]])), 2) for k, r in rows.items()})
