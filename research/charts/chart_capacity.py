"""Chart 3 — capacity: validation PSNR, SSIM and L_fre against the decoded NBRDF's size
(6→21→21→3 … 6→60×4→3) and the latent size, against NBRDF evaluation throughput
(queries/s, one CPU thread) and bytes per material, with the Pareto front. Regenerate
with the one command

    OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 python research/charts/chart_capacity.py --data frenbrdf-demo/data --seeds 0 1

(the 100-material synthetic bank of ``frenbrdf synth``; 14 runs of 50 epochs, about 20
minutes on one CPU thread after chart 2, whose two default runs it reuses). Writes
``research/figures/chart3_capacity.{png,csv,json}``; the training runs go to
``bench-results/sweeps/runs/`` and are reused (resumable). ``frenbrdf select --front
research/figures/chart3_capacity.json`` picks the smallest configuration reaching a PSNR from it.
"""

import sys

from sweeps import chart_main

if __name__ == "__main__":
    sys.exit(chart_main("capacity", doc=__doc__))
