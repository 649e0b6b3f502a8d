"""Training-step time of each method at default settings, and the share of L_fre.

    python benches/train_step.py [--data DIR] [--steps 20] [--device cpu|cuda]

Without ``--data`` it writes 16 materials of the default synthetic bank to a temporary
folder. For FreNBRDF it times the same step with and without the frequency term (same
model, same samples), so the difference is what L_fre adds; it also times the parts of
L_fre alone. Writes ``bench-results/train_step.{md,json}``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import torch

from frenbrdf.data import list_materials, split_materials
from frenbrdf.losses import FrequencyLoss
from frenbrdf.models import AutoEncoder
from frenbrdf.training import _Distributed, _prepare, config_for, loss_terms


def median_seconds(functions: dict, steps: int, device: torch.device) -> dict[str, float]:
    """Median time of each function, calls interleaved so that drift affects all alike."""
    times: dict[str, list[float]] = {name: [] for name in functions}
    for i in range(steps + 3):  # 3 warm-up rounds
        for name, function in functions.items():
            if device.type == "cuda":
                torch.cuda.synchronize()
            start = time.perf_counter()
            function()
            if device.type == "cuda":
                torch.cuda.synchronize()
            if i >= 3:
                times[name].append(time.perf_counter() - start)
    return {name: statistics.median(values) for name, values in times.items()}


def time_method(method: str, data: Path, steps: int, device: torch.device, slices=None) -> dict:
    cfg = config_for(method, data=str(data), out="", progress=False, cache_dir=str(data / ".cache"))
    if slices is not None:
        cfg.loss.frequency.slices = slices
    files = {path.stem: path for path in list_materials(data)}
    split = split_materials(files, seed=0)
    _, bank, truth = _prepare(cfg, split, files, _Distributed())
    torch.manual_seed(0)
    network = AutoEncoder(cfg.model).to(device)
    frequency = FrequencyLoss(cfg.loss.frequency).to(device)
    optimizer = torch.optim.Adam(network.parameters(), lr=cfg.lr)
    generator = torch.Generator().manual_seed(0)
    batch = list(range(min(cfg.batch_materials, len(split.train))))
    context = bank.sample(batch, cfg.context_samples, generator).to(device)
    query = bank.sample(batch, cfg.query_samples, generator).to(device)
    true = truth[batch].to(device) if truth is not None else None

    def step(with_frequency: bool):
        terms = loss_terms(network, frequency if with_frequency else None, cfg.loss, context, query,
                           true if with_frequency else None)
        optimizer.zero_grad(set_to_none=True)
        terms.total.backward()
        optimizer.step()

    result = {"method": method, "nbrdf_hidden": list(cfg.model.nbrdf.hidden), "batch_materials": len(batch),
              "samples": [cfg.context_samples, cfg.query_samples], "eta": cfg.loss.eta}
    if cfg.loss.eta == 0:
        result["step_s"] = median_seconds({"step": lambda: step(False)}, steps, device)["step"]
        return result
    params = [p.detach().requires_grad_() for p in network(context.encoder_input())[1]]
    timed = median_seconds({"step": lambda: step(True), "without": lambda: step(False),
                            "nbrdf_eval": lambda: frequency.predicted_maps(params),
                            "fre": lambda: frequency(params, true).backward()}, steps, device)
    result.update(step_s=timed["step"], step_without_fre_s=timed["without"],
                  fre_added_share=timed["step"] / timed["without"] - 1,
                  fre_nbrdf_eval_s=timed["nbrdf_eval"], fre_forward_backward_s=timed["fre"])
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path)
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--device", default="cpu")
    parser.add_argument("--slices", help="θ_h bin indices of the L_fre slices, e.g. 0,24,48,72 (default: the config's)")
    parser.add_argument("--out", type=Path, default=Path("bench-results"))
    args = parser.parse_args()
    device = torch.device(args.device)
    with tempfile.TemporaryDirectory() as scratch:
        data = args.data
        if data is None:
            from frenbrdf.synth import write_bank

            data = Path(scratch)
            write_bank(data, n=16, seed=0, progress=False)
        slices = tuple(int(i) for i in args.slices.split(",")) if args.slices else None
        results = [time_method(method, data, args.steps, device, slices) for method in ("frenbrdf", "nbrdf", "hyperbrdf")]
    lines = [f"Training step at default settings on {device} (torch threads: {torch.get_num_threads()}), "
             f"median of {args.steps} steps; L_fre slices: {args.slices or 'default'}.", "",
             "| method | NBRDF | step (ms) | without L_fre (ms) | L_fre adds |", "|---|---|---|---|---|"]
    for r in results:
        without = f"{1e3 * r['step_without_fre_s']:.1f}" if "step_without_fre_s" in r else "–"
        share = f"{100 * r['fre_added_share']:.0f} %" if "fre_added_share" in r else "–"
        lines.append(f"| {r['method']} | 6→{'→'.join(map(str, r['nbrdf_hidden']))}→3 | {1e3 * r['step_s']:.1f} | "
                     f"{without} | {share} |")
    fre = results[0]
    lines += ["", f"L_fre alone: NBRDF at the grid nodes {1e3 * fre['fre_nbrdf_eval_s']:.1f} ms; "
                  f"forward + backward (incl. SHT and its adjoint) {1e3 * fre['fre_forward_backward_s']:.1f} ms."]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "train_step.md").write_text("\n".join(lines) + "\n")
    (args.out / "train_step.json").write_text(json.dumps(results, indent=2) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
