"""Where an attention encoder looks: each sample's pooling weight, drawn over (θ_h, θ_d), per head and pattern.

    python research/results/attention-pooling/weights.py local/v5/release/work/data/red-phenolic.binary \\
        --out research/results/attention-pooling/weights.png

The shipped model's first attention-pooled encoder reads the table through random bins and uniform pairs (4,000
each, draw 0 as compare_models.py draws them); each panel is one head under one pattern, every sample a dot at its
(θ_h, θ_d), coloured by its weight times the number of samples (1: the plain mean's weight).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

from frenbrdf.io import read_material  # noqa: E402
from frenbrdf.io.patterns import pattern_samples  # noqa: E402
from frenbrdf.io.sampling import as_table  # noqa: E402
from frenbrdf.models.autoencoder import load_model  # noqa: E402
from frenbrdf.models.nbrdf import mapped_samples  # noqa: E402
from frenbrdf.numerics.coords import directions_to_rusinkiewicz  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "studies"))
from compare_models import condition_rng  # noqa: E402

PATTERNS = ("merl-bins", "uniform")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("table", type=Path, help="a MERL table")
    parser.add_argument("--model", default="pretrained")
    parser.add_argument("--samples", type=int, default=4000)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    model = load_model(args.model)
    encoder = next((e for e in model.network.encoder.encoders() if e.pooling == "attention"), None)
    if encoder is None:
        raise SystemExit(f"{args.model} has no attention-pooled encoder")
    truth = read_material(args.table)
    table = as_table(truth)
    figure, axes = plt.subplots(len(PATTERNS), encoder.heads, figsize=(3.2 * encoder.heads, 3.0 * len(PATTERNS)),
                                squeeze=False, sharex=True, sharey=True, layout="constrained")
    norm = LogNorm(0.1, 10)
    for row, pattern in enumerate(PATTERNS):
        values, (wi, wo) = pattern_samples(truth, pattern, args.samples, condition_rng(0, pattern), table=table)
        mapped, coords, _ = mapped_samples(model.mapping, values, (wi, wo))
        samples = torch.from_numpy(np.concatenate([mapped, coords], axis=-1).astype(np.float32))[None]
        with torch.no_grad():
            weights = encoder.attention_weights(samples)[0].numpy() * len(values)
        angles = np.degrees(directions_to_rusinkiewicz(wi, wo))
        for head in range(encoder.heads):
            ax = axes[row, head]
            points = ax.scatter(angles[:, 0], angles[:, 2], c=np.clip(weights[:, head], 0.1, 10), s=2, norm=norm,
                                cmap="viridis")
            ax.set_title(f"{pattern}, head {head + 1}", fontsize=9)
            ax.set_xlabel("θ_h (°)") if row == len(PATTERNS) - 1 else None
            ax.set_ylabel("θ_d (°)") if head == 0 else None
    figure.colorbar(points, ax=axes, label="weight × samples (1: the mean's)", shrink=0.8)
    figure.suptitle(f"{args.table.stem}: where the attention encoder looks", fontsize=11)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(args.out, dpi=90)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
