"""The report of the SHT peer comparison (``benches/peers/sht_peers.py``): markdown tables and the
two charts of chart 1, from the results dict that ``sht_peers.json`` holds.
"""

from __future__ import annotations

from pathlib import Path

from sht_setup import BIG_BATCH, BIG_NLAT, BUSY_SHARE, GL_SIZES, LIBRARIES, MIN_SAMPLE_S, PEERS, TOLERANCE, WORKLOAD

from common import pyplot, save_figure


def key_of(row: dict) -> str:
    return f"{row['library']} {row['dtype']}"


def key_order(key: str) -> tuple[int, int]:
    library, dtype = key.split()
    return LIBRARIES.index(library), ("float64", "float32").index(dtype)


def fmt(value, spec: str, missing: str = "—") -> str:
    return missing if value is None else format(value, spec)


def build_markdown(data: dict) -> str:
    """The tables of sht_peers.md; also sets ``data["workload_ratios"]``."""
    meta, timings, checks = data["meta"], data["timings"], data["checks"]
    threads_list = meta["threads"]
    lines = ["# Spherical harmonic transform: frenbrdf against peers", ""]
    lines.append(f"Machine: {meta['cores']} cores, {meta['platform']}; load average (1, 5, 15 min) before / after: {meta['load_before']} / {meta['load_after']}. "
                 f"Median of up to {meta['repeats']} samples after a warm-up, each at least {MIN_SAMPLE_S * 1e3:.0f} ms of back-to-back calls. Mode: {'quick' if meta['quick'] else 'full'}. "
                 f"OMP_WAIT_POLICY: {meta['omp_wait_policy'] or 'unset (OpenMP default)'}.")
    lines.append("")
    busy = {f"{r['library']} ({r['threads']} thr)": r["background_cpu"] for r in data["workers"] if (r["background_cpu"] or 0) > BUSY_SHARE}
    if busy:
        worst = max(busy.values())
        lines += [f"**Warning:** other processes used up to {worst:.0%} of the machine's CPU during this run "
                  f"({', '.join(f'{k}: {v:.0%}' for k, v in busy.items())}); those timings, multi-threaded ones above all "
                  "(OpenMP barriers in particular), are unreliable. Re-run on an idle machine.", ""]
    lines.append("| library | version | status |")
    lines.append("|---|---|---|")
    for name, info in data["libraries"].items():
        status = "used" if info["available"] else f"skipped: {info.get('reason', '?')}"
        notes = "; ".join(sorted(set(info.get("notes", []))))
        lines.append(f"| {name} | {info.get('version', '—')} | {status}{'; ' + notes if notes else ''} |")

    w = WORKLOAD
    lines += ["", f"## Workload: {w['batch']} maps (3 x 64), Gauss-Legendre {w['nlat']}x{w['nlon']}, lmax {w['lmax']}: analysis throughput (maps/s)", ""]
    lines.append("| library | dtype | " + " | ".join(f"{t} thread{'s' if t > 1 else ''}" for t in threads_list) + " |")
    lines.append("|---|---|" + "---|" * len(threads_list))

    def workload_rate(library, dtype, threads):
        for row in timings:
            if (row["library"], row["dtype"], row["threads"], row["grid"], row["nlat"], row["batch"]) == (library, dtype, threads, "gauss", w["nlat"], w["batch"]):
                return row["maps_per_s"]
        return None

    for library in LIBRARIES:
        for dtype in ("float64", "float32"):
            rates = [workload_rate(library, dtype, t) for t in threads_list]
            if any(r is not None for r in rates):
                lines.append(f"| {library} | {dtype} | " + " | ".join(fmt(r, ",.0f") for r in rates) + " |")
    has_ours = any(workload_rate("frenbrdf", d, t) for d in ("float64", "float32") for t in threads_list)
    lines += ["", "Throughput ratio ours/peer (same thread count and dtype; > 1 means frenbrdf is faster):", ""]
    ratios, ratio_rows = {}, []
    for peer in PEERS:
        for dtype in ("float64", "float32"):
            values = []
            for t in threads_list:
                ours, theirs = workload_rate("frenbrdf", dtype, t), workload_rate(peer, dtype, t)
                value = ours / theirs if ours and theirs else None
                values.append(value)
                ratios[f"ours/{peer} {dtype} {t} threads"] = value
            if any(v is not None for v in values):
                ratio_rows.append(f"| {peer} | {dtype} | " + " | ".join(fmt(v, ".2f") + ("×" if v else "") for v in values) + " |")
    if ratio_rows:
        lines.append("| peer | dtype | " + " | ".join(f"{t} thread{'s' if t > 1 else ''}" for t in threads_list) + " |")
        lines.append("|---|---|" + "---|" * len(threads_list))
        lines += ratio_rows
    else:
        lines.append("(no ratios: " + ("no peer was measured" if has_ours else "frenbrdf was not measured") + ".)")
    data["workload_ratios"] = ratios

    for size_threads in meta["size_threads"]:
        size_rows = [r for r in timings if r["threads"] == size_threads and r["grid"] == "gauss"]
        columns = sorted({key_of(r) for r in size_rows}, key=key_order)
        if not size_rows:
            continue
        lines += ["", f"## Analysis time per map (ms), Gauss-Legendre, lmax = nlat - 1, {size_threads} thread{'s' if size_threads > 1 else ''}", ""]
        if any(r["nlat"] == BIG_NLAT for r in size_rows):
            lines.append(f"The {BIG_NLAT}x{2 * BIG_NLAT} batch row uses {BIG_BATCH} maps, not 192, to keep time and memory in bounds.")
            lines.append("")
        lines.append("| grid | lmax | batch | " + " | ".join(columns) + " |")
        lines.append("|---|---|---|" + "---|" * len(columns))
        for nlat, nlon in GL_SIZES:
            for batch in sorted({r["batch"] for r in size_rows if r["nlat"] == nlat}):
                cells = []
                for column in columns:
                    match = [r for r in size_rows if r["nlat"] == nlat and r["batch"] == batch and key_of(r) == column]
                    cells.append(fmt(match[0]["per_map_s"] * 1e3 if match else None, ".3f"))
                lines.append(f"| {nlat}x{nlon} | {nlat - 1} | {batch} | " + " | ".join(cells) + " |")

    if checks:
        check_threads = max(c["threads"] for c in checks)
        rows = [c for c in checks if c["threads"] == check_threads]
        columns = sorted({key_of(c) for c in rows}, key=key_order)
        lines += ["", f"## Accuracy against the float64 reference ({meta['reference']}): analysis error / synthesis error", ""]
        lines.append("Max |difference| / max |reference|, over a batch of 2 random band-limited fields; a_lm compared as complex [l, m] "
                     "arrays in ducc0's convention (orthonormal, Condon-Shortley phase). "
                     f"Pass: both ≤ {TOLERANCE['float64']:g} (float64), ≤ {TOLERANCE['float32']:g} (float32). "
                     "Analysis error: the library's analysis of the reference map against the a_lm it was made from. "
                     "Synthesis error: the library's synthesis of those a_lm against the reference map "
                     "(zero for ducc0 float64 when ducc0 made the reference; the other libraries' synthesis errors are the cross-check of the reference).")
        lines.append("")
        lines.append("| grid | size | lmax | " + " | ".join(columns) + " |")
        lines.append("|---|---|---|" + "---|" * len(columns))
        grids = sorted({(c["grid"], c["nlat"], c["nlon"], c["lmax"]) for c in rows}, key=lambda g: (g[0] != "gauss", g[1]))
        for grid, nlat, nlon, lmax in grids:
            cells = []
            for column in columns:
                match = [c for c in rows if (c["grid"], c["nlat"], c["lmax"]) == (grid, nlat, lmax) and key_of(c) == column]
                if not match:
                    cells.append("—")
                elif "error" in match[0]:
                    cells.append("error")
                elif "analysis_err" not in match[0]:
                    cells.append("unchecked")
                else:
                    c = match[0]
                    cells.append(f"{c['analysis_err']:.1e} / {c['synthesis_err']:.1e}" + ("" if c["ok"] else " FAIL"))
            lines.append(f"| {'Gauss-Legendre' if grid == 'gauss' else 'equiangular (CC)'} | {nlat}x{nlon} | {lmax} | " + " | ".join(cells) + " |")
        failures = [c for c in checks if not c["ok"]]
        if failures:
            lines += ["", "Failed checks (not timed):", ""]
            for c in failures:
                detail = c.get("error") or f"analysis {c['analysis_err']:.2e}, synthesis {c['synthesis_err']:.2e}" + (f"; {c['hint']}" if "hint" in c else "")
                lines.append(f"- {key_of(c)} {c['grid']} {c['nlat']}x{c['nlon']} lmax {c['lmax']} ({c['threads']} thread{'s' if c['threads'] > 1 else ''}): {detail}")
    return "\n".join(lines) + "\n"


def lmax_axis(ax, values: list[int]) -> None:
    from matplotlib.ticker import NullLocator

    ax.set_xscale("log", base=2)
    ax.set_xticks(values, [str(v) for v in values])
    ax.xaxis.set_minor_locator(NullLocator())


def plot(data: dict, out: Path) -> list[str]:
    """Writes sht_time_vs_lmax.png and sht_error_vs_lmax.png to ``out``; returns their names (or why not)."""
    try:
        plt = pyplot()
    except ImportError as error:
        return [f"charts skipped: {error}"]
    size_threads = data["meta"]["size_threads"]
    rows = [r for r in data["timings"] if r["threads"] in size_threads and r["grid"] == "gauss"]
    styles = {"float64": "-", "float32": "--"}
    colours = dict(zip(LIBRARIES, ("C3", "C0", "C2", "C1"), strict=True))
    written = []
    if not rows:
        return ["time chart skipped: no size-sweep timings"]

    fig, axes = plt.subplots(len(size_threads), 2, figsize=(11, 4.2 * len(size_threads)), sharey=True, squeeze=False)
    for row_axes, threads in zip(axes, size_threads, strict=True):
        for ax, single in zip(row_axes, (True, False), strict=True):
            subset = [r for r in rows if (r["batch"] == 1) == single and r["threads"] == threads]
            for key in sorted({key_of(r) for r in subset}, key=key_order):
                points = sorted((r["lmax"], r["per_map_s"] * 1e3) for r in subset if key_of(r) == key)
                library, dtype = key.split()
                ax.plot(*zip(*points, strict=True), styles[dtype], marker="o", color=colours[library], label=key)
            lmax_axis(ax, sorted({r["lmax"] for r in rows}))
            ax.set_yscale("log")
            ax.set_xlabel("lmax (Gauss-Legendre, nlat = lmax + 1, nlon = 2 nlat)")
            batch = "batch 1" if single else f"batch 192 ({BIG_BATCH} at {BIG_NLAT}x{2 * BIG_NLAT})"
            ax.set_title(f"{batch}, {threads} thread{'s' if threads > 1 else ''}")
            ax.grid(True, which="both", alpha=0.3)
        row_axes[0].set_ylabel("analysis time per map (ms)")
    axes[0][1].legend(fontsize=8)
    fig.suptitle("SHT analysis time per map vs lmax (lower is better)")
    fig.tight_layout()
    save_figure(fig, out / "sht_time_vs_lmax.png", dpi=120)
    written.append("sht_time_vs_lmax.png")

    checks = [c for c in data["checks"] if c["grid"] == "gauss" and "analysis_err" in c]
    if checks:
        check_threads = max(c["threads"] for c in checks)
        checks = [c for c in checks if c["threads"] == check_threads]
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
        for ax, field, title in zip(axes, ("analysis_err", "synthesis_err"), ("analysis: max |â - a| / max |a|", "synthesis: max |f̂ - f| / max |f|"), strict=True):
            for key in sorted({key_of(c) for c in checks}, key=key_order):
                points = sorted((c["lmax"], max(c[field], 1e-17)) for c in checks if key_of(c) == key)
                library, dtype = key.split()
                exact = field == "synthesis_err" and all(y <= 1e-17 for _, y in points)
                label = key + (" (is the reference: 0, drawn at 1e-17)" if exact else "")
                ax.plot(*zip(*points, strict=True), styles[dtype], marker="o", color=colours[library], label=label)
            lmax_axis(ax, sorted({c["lmax"] for c in checks}))
            ax.set_yscale("log")
            ax.set_xlabel("lmax (Gauss-Legendre)")
            ax.set_title(title)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].set_ylabel("max relative error vs float64 reference")
        axes[1].legend(fontsize=8)
        fig.suptitle(f"SHT round-trip error vs lmax (reference: {data['meta']['reference']})")
        fig.tight_layout()
        save_figure(fig, out / "sht_error_vs_lmax.png", dpi=120)
        written.append("sht_error_vs_lmax.png")
    return written


def save_report(data: dict, markdown: str, out: Path) -> list[str]:
    """Writes sht_peers.md, sht_peers.json, sht_timings.csv, sht_errors.csv and the charts to ``out``
    (atomically, :mod:`frenbrdf.io.atomic`); returns what :func:`plot` returns."""
    from frenbrdf.io.atomic import save_csv, save_json, write_text

    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "sht_peers.md", markdown)
    save_json(out / "sht_peers.json", data)
    save_csv(out / "sht_timings.csv", data["timings"])
    save_csv(out / "sht_errors.csv", data["checks"])
    return plot(data, out)
