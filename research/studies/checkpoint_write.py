"""What keeping f_ref out of the checkpoints saves: the time of writing one epoch's two
checkpoints (``best.pt`` and ``last.pt``, the demo's FreNBRDF model) with the 17.5 MB
per-bin f_ref table inside (checkpoint format 1) and without it (format 2, the mapping
written once per run folder), and the file sizes.

    python research/studies/checkpoint_write.py [--rounds 15] [--out DIR]
"""
import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import torch

from frenbrdf.configs import to_dict
from frenbrdf.io import checkpoints
from frenbrdf.models.autoencoder import AutoEncoder
from frenbrdf.training import config_for

parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
parser.add_argument("--rounds", type=int, default=15, help="epochs' worth of writes per variant (default 15)")
parser.add_argument("--out", type=Path, help="folder to write to (default: a temporary folder)")
args = parser.parse_args()
cfg = config_for("frenbrdf", training="demo")
network = AutoEncoder(cfg.model)
optimizer = torch.optim.Adam(network.parameters())
network(torch.zeros(1, 10, 9))[0].sum().backward()
optimizer.step()  # the optimiser state of a trained model
state = {"method": "frenbrdf", "config": json.dumps(to_dict(cfg)), "model": network.state_dict(),
         "optimizer": optimizer.state_dict(), "generator": torch.Generator().get_state(), "epoch": 0, "history": []}
reference = torch.rand(3, 90, 90, 180, dtype=torch.float32)
variants = {"with f_ref (format 1)": {**state, "mapping": {"reference": reference, "epsilon": 0.002}},
            "without (format 2)": state}
times: dict[str, list[float]] = {name: [] for name in variants}
sizes: dict[str, int] = {}
with tempfile.TemporaryDirectory() as scratch:
    out = args.out or Path(scratch)
    out.mkdir(parents=True, exist_ok=True)
    for _ in range(args.rounds):  # interleaved, so that drift affects both alike
        for name, epoch_state in variants.items():
            start = time.perf_counter()
            for file in ("best.pt", "last.pt"):
                checkpoints.save(out / file, epoch_state)
            times[name].append(time.perf_counter() - start)
            sizes[name] = (out / "last.pt").stat().st_size
for name, seconds in times.items():
    print(f"{name:>22}: {sizes[name] / 1e6:6.2f} MB per checkpoint; two per epoch: median "
          f"{1e3 * statistics.median(seconds):.1f} ms, min {1e3 * min(seconds):.1f} ms")
