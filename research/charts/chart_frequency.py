"""Chart 2 — the frequency loss: training-step time, validation PSNR and L_fre against
L_fre's band limit lmax, number of θ_h slices, kNN k and σ (one varied at a time around
the default). Regenerate with the one command

    OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 python research/charts/chart_frequency.py --data frenbrdf-demo/data --seeds 0 1

(the 100-material synthetic bank of ``frenbrdf synth``; 18 runs of 50 epochs, about 30
minutes on one CPU thread). Writes ``research/figures/chart2_frequency.{png,csv,json}``. The
training runs go to ``bench-results/sweeps/runs/`` and are reused: a second call only
measures what is missing, an interrupted one resumes, and chart 3
(``research/charts/chart_capacity.py``) shares the default runs. See ``research/charts/sweeps.py`` and ``frenbrdf.evaluation.variants`` for what
is measured and how, and ``research/figures/README.md`` for the reading.
"""

import sys

from sweeps import chart_main

if __name__ == "__main__":
    sys.exit(chart_main("frequency", doc=__doc__))
