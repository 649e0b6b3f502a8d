"""The tables of an evaluation (:mod:`frenbrdf.evaluation.evaluate`): its rows, the paper's numbers, the Markdown.

Every function here reads a report's JSON-ready dicts (``summary``, ``reconstruction``,
``evaluation_set``, ``colour``, ``rendered``), so a table can be rewritten from
``evaluation.json`` without evaluating again.
"""

from __future__ import annotations

import numpy as np

from .statistics import markdown

#: The paper's numbers (MERL, their protocol), docs/method.md §7.
#: Its L_fre (×10³: hyperbrdf 6.74, nbrdf 6.80, frenbrdf 0.23) is a mean over coefficients on its own
#: data and settings, not comparable with ours (normalised on the sphere), so it is not listed.
PAPER = {
    "hyperbrdf": {"rmse_x100": 6.89, "psnr": 26.3, "ssim_x10": 9.26, "edit_psnr": 22.4, "edit_ssim_x10": 9.13},
    "nbrdf": {"rmse_x100": 6.60, "psnr": 29.2, "ssim_x10": 9.50, "edit_psnr": 27.6, "edit_ssim_x10": 9.42},
    "frenbrdf": {"rmse_x100": 6.74, "psnr": 29.9, "ssim_x10": 9.88, "edit_psnr": 30.1, "edit_ssim_x10": 9.82},
}
RECONSTRUCTION_ROWS = [("rmse_x100", "Recon RMSE×10² ↓"), ("psnr", "Recon PSNR ↑"), ("ssim_x10", "Recon SSIM×10 ↑"),
                       ("lfre", "Recon L_fre ↓"), ("delta_e", "Recon ΔE ↓"),
                       ("highlight_psnr", "Recon highlight PSNR ↑"), ("highlight_delta_e", "Recon highlight ΔE ↓")]
EDITING_ROWS = [("edit_psnr", "Edit PSNR ↑"), ("edit_ssim_x10", "Edit SSIM×10 ↑"), ("edit_delta_e", "Edit ΔE ↓"),
                ("edit_highlight_psnr", "Edit highlight PSNR ↑")]
#: The keys of the highlight rows (PSNR and ΔE over the truth's 5 % brightest lit pixels): a report written before
#: they existed has none, and its tables leave them out.
HIGHLIGHT_KEYS = ("highlight_psnr", "highlight_delta_e", "edit_highlight_psnr", "refined_highlight_psnr")
#: The rows of every table (summary key, label): the paper's protocol, the encoder's latent.
ROWS = RECONSTRUCTION_ROWS + EDITING_ROWS
#: What a refinement budget (:data:`frenbrdf.models.reconstruct.BUDGETS`) refines, as its rows name it.
REFINED = {"latent": "refined z", "full": "refined z + weights"}


def pattern_suffix(pattern: str, patterns) -> str:
    """What a sampling pattern's metric keys end with in a report evaluated from ``patterns``
    (:attr:`frenbrdf.evaluation.evaluate.EvaluateConfig.patterns`): nothing for the first, ``@<pattern>`` for
    another."""
    return "" if pattern == patterns[0] else f"@{pattern}"


def table_rows(refine: str = "none", patterns=()) -> list[tuple[str, str]]:
    """The rows of a table: :data:`ROWS` and, when test-time refinement ``refine`` (a budget name) ran, the
    refined rows after the encoder's of each block. Editing interpolates refined latents whatever the budget
    (refined weights have no latent), so its rows say "refined z".

    With several sampling ``patterns`` (a report's ``config["patterns"]``) the reconstruction rows come once per
    pattern, each labelled with its name (``uniform: Recon PSNR ↑``; keys ``<key>@<pattern>`` after the first),
    then the editing rows, which interpolate the first pattern's latents."""
    if refine == "none":
        rows = list(ROWS)
    else:
        refined = REFINED.get(refine, f"refined ({refine})")
        rows = [*RECONSTRUCTION_ROWS, ("refined_psnr", f"Recon PSNR, {refined} ↑"),
                ("refined_lfre", f"Recon L_fre, {refined} ↓"), ("refined_delta_e", f"Recon ΔE, {refined} ↓"),
                ("refined_highlight_psnr", f"Recon highlight PSNR, {refined} ↑"),
                *EDITING_ROWS, ("edit_refined_psnr", "Edit PSNR, refined z ↑"),
                ("edit_refined_delta_e", "Edit ΔE, refined z ↓")]
    if len(patterns) < 2:
        return rows
    reconstruction = [row for row in rows if not row[0].startswith("edit_")]
    return [*((key + pattern_suffix(pattern, patterns), f"{pattern}: {label}") for pattern in patterns
              for key, label in reconstruction), *(row for row in rows if row[0].startswith("edit_"))]


def summarise(rows: list[dict], edit_rows: list[dict]) -> dict[str, float | None]:
    """The table's numbers of one method: means over its reconstruction ``rows`` and its ``edit_rows``
    (None without edits: ``null`` in ``evaluation.json``); the refined ones too when the rows hold them, and each
    further sampling pattern's (row keys ``<key>@<pattern>``: summary keys ``<summary key>@<pattern>``)."""
    summary = _summary(rows, edit_rows)
    suffixes = dict.fromkeys("@" + key.partition("@")[2] for key in (rows[0] if rows else {}) if "@" in key)
    for suffix in suffixes:
        drawn = [{key.removesuffix(suffix): value for key, value in row.items() if key.endswith(suffix)}
                 for row in rows]
        summary.update({key + suffix: value for key, value in _summary(drawn, []).items()
                        if not key.startswith("edit_")})
    return summary


def _summary(rows: list[dict], edit_rows: list[dict]) -> dict[str, float | None]:
    """:func:`summarise` of one pattern's rows (plain keys)."""
    def mean(values, key, scale=1.0):
        return scale * float(np.mean([r[key] for r in values])) if values else None

    summary = {"rmse_x100": mean(rows, "rmse", 100), "psnr": mean(rows, "psnr"), "ssim_x10": mean(rows, "ssim", 10),
               "lfre": mean(rows, "lfre"), "delta_e": mean(rows, "delta_e"), "edit_psnr": mean(edit_rows, "psnr"),
               "edit_ssim_x10": mean(edit_rows, "ssim", 10), "edit_delta_e": mean(edit_rows, "delta_e")}
    if rows and "highlight_psnr" in rows[0]:
        summary.update(highlight_psnr=mean(rows, "highlight_psnr"), highlight_delta_e=mean(rows, "highlight_delta_e"),
                       edit_highlight_psnr=mean(edit_rows, "highlight_psnr"))
    if rows and "refined_psnr" in rows[0]:
        summary.update(refined_psnr=mean(rows, "refined_psnr"), refined_lfre=mean(rows, "refined_lfre"),
                       refined_delta_e=mean(rows, "refined_delta_e"),
                       **({"refined_highlight_psnr": mean(rows, "refined_highlight_psnr")}
                          if "refined_highlight_psnr" in rows[0] else {}),
                       edit_refined_psnr=mean(edit_rows, "refined_psnr"),
                       edit_refined_delta_e=mean(edit_rows, "refined_delta_e"))
    return summary
#: ΔE above which two colours read as different (:func:`frenbrdf.render.scoring.delta_e`); reports count the materials above it.
DIFFERENT_COLOUR = 5.0
#: Materials per method that a report lists as where colour is lost most.
WORST_LISTED = 5


def colour_losses(per_material: dict[str, list[dict]], worst: int = WORST_LISTED) -> dict[str, dict]:
    """Where each method loses colour: how many materials read as a different colour (ΔE above
    :data:`DIFFERENT_COLOUR`) and the ``worst`` with the highest ΔE (material, ΔE, PSNR).

    Rows of one material (several seeds that evaluated it) are averaged first.
    """
    losses = {}
    for method, rows in per_material.items():
        by_name: dict[str, list[dict]] = {}
        for row in rows:
            by_name.setdefault(row["material"], []).append(row)
        materials: list[dict] = sorted(({"material": name, "delta_e": float(np.mean([r["delta_e"] for r in group])),
                             "psnr": float(np.mean([r["psnr"] for r in group]))} for name, group in by_name.items()),
                           key=lambda m: -m["delta_e"])
        losses[method] = {"materials": len(materials), "worst": materials[:worst],
                          "different": sum(m["delta_e"] > DIFFERENT_COLOUR for m in materials)}
    return losses


def seeds_markdown(report: dict) -> str:
    """The over-seeds table of :func:`~frenbrdf.evaluation.evaluate.evaluate_seeds`, with what was measured."""
    first = next(iter(report["seeds"].values()))
    n_edits = sum(len(e) for e in first["editing"].values()) // max(1, len(first["summary"]))
    evaluated = report["evaluation_set"]
    materials = (f"the same {evaluated['materials']} materials for every seed" if evaluated["out_of_distribution"]
                 else f"each seed's test materials ({report['test_materials']} in all)")
    patterns = first["config"].get("patterns", ["merl-bins"])
    rows = table_rows(first["config"].get("refine", "none"), patterns)
    left_out = [label for key, label in rows if key not in report["comparison"]["metrics"]]
    refined = first.get("refinement")
    return (evaluation_set_markdown(evaluated) + "\n\n" + patterns_markdown(patterns, first["config"]["samples"])
            + "\n\n"
            + (refinement_markdown(refined, first["config"]["samples"]) + "\n\n" if refined else "")
            + f"Reconstruction on {materials}; editing over {n_edits} interpolations per seed (each unordered pair of "
            "evaluated materials at most once, t ∈ {0.25, 0.5, 0.75}). RMSE, PSNR, SSIM and ΔE over the lit material "
            "pixels (background excluded); L_fre normalised on the sphere (docs/method.md §5). Per seed: "
            "`seed-S/evaluation.md`."
            + (f" Left out, not finite on every seed: {', '.join(left_out)}." if left_out else "") + "\n\n"
            + markdown(report["comparison"], dict(rows)) + "\n"
            + colour_markdown(report["colour"], "averaged over the seeds that evaluated it"
                              + ("; encoder only" if refined else "")))


def patterns_markdown(patterns, samples: int) -> str:
    """How the samples were drawn (a report's ``config["patterns"]``, :mod:`frenbrdf.io.patterns`), in a sentence or
    two."""
    names = ", ".join(f"`{name}`" for name in patterns)
    if len(patterns) == 1:
        return f"Each material encoded from {samples} samples drawn by the sampling pattern {names}."
    return (f"Each material encoded from {samples} samples of each sampling pattern: {names}. The reconstruction "
            "rows come once per pattern, labelled with its name (the paper's numbers, from random MERL bins, beside "
            f"the first only); editing, the renders and the spectra use the first pattern's (`{patterns[0]}`) "
            "latents.")


def evaluation_set_markdown(evaluated: dict) -> str:
    """What a report evaluated (the ``evaluation_set`` of a report), in a sentence or two."""
    text = (f"Evaluation set: {evaluated['description']}. The runs were trained on "
            + ", ".join(f"`{folder}`" for folder in evaluated["trained_on"]) + ".")
    excluded = evaluated["excluded"]
    if evaluated["out_of_distribution"] and excluded:
        text += (f" Left out {len(excluded)} material{'s' * (len(excluded) != 1)} of `{evaluated['data']}` that a "
                 f"run trained or validated on: {', '.join(excluded)}.")
    elif evaluated["out_of_distribution"]:
        text += f" No material of `{evaluated['data']}` was left out: no run trained or validated on any of them."
    return text


def colour_markdown(colour: dict, per_material: str = "") -> str:
    """Where colour is lost (:func:`colour_losses`), one row per method; ``per_material`` says how a
    material's ΔE was obtained, when not from one evaluation."""
    lines = [f"ΔE is the mean CIEDE2000 colour difference over the lit pixels (≈ 1: the smallest difference a person "
             f"sees side by side; above {DIFFERENT_COLOUR:g} the colours read as different). Per method, the "
             f"materials with the highest ΔE{f' ({per_material})' if per_material else ''}:", "",
             f"| method | ΔE > {DIFFERENT_COLOUR:g} | highest ΔE: material (ΔE, PSNR) |", "|---|---|---|"]
    for method, losses in colour.items():
        worst = "; ".join(f"{m['material']} ({m['delta_e']:.1f}, {m['psnr']:.1f} dB)" for m in losses["worst"])
        lines.append(f"| {method} | {losses['different']} of {losses['materials']} | {worst} |")
    return "\n".join(lines) + "\n"


def report_markdown(report: dict) -> str:
    """The Markdown of a report of :func:`~frenbrdf.evaluation.evaluate.evaluate_runs`: what was evaluated, the
    table, where colour is lost and which materials ``renders.png`` shows."""
    n_edits = sum(len(e) for e in report["editing"].values()) // max(1, len(report["summary"]))
    evaluated = report["evaluation_set"]
    noun = "materials" if evaluated["out_of_distribution"] else "test materials"
    first, hardest = report["rendered"]["first"], report["rendered"]["highest_delta_e"]
    rendered = (f"`renders.png` shows the first {len(first)} materials by name ({', '.join(first)})"
                + (f" and the {len(hardest)} others with the highest ΔE averaged over the methods "
                   f"({', '.join(hardest)}), so the hard cases are always in the picture." if hardest else "."))
    refined = report.get("refinement")
    if refined:
        rendered += " Beside each method's render, its refined one (`<method> refined`)."
    patterns = report["config"].get("patterns", ["merl-bins"])  # a report from before patterns: merl-bins
    return "\n".join([evaluation_set_markdown(evaluated), "", patterns_markdown(patterns, report["config"]["samples"]),
                      "", *([refinement_markdown(refined, report["config"]["samples"]), ""] if refined else []),
                      markdown_table(report["summary"], len(report["test_materials"]), n_edits, materials=noun,
                                     refine=report["config"].get("refine", "none"), patterns=patterns),
                      colour_markdown(report["colour"], "encoder only" if refined else ""), rendered, ""])


def refinement_markdown(refinement: dict, samples: int) -> str:
    """What the encoder-only and the refined rows each mean (the ``refinement`` of a report), with the seconds
    refinement took per material."""
    budget, steps = refinement["budget"], refinement["config"]
    stages = f"{steps['latent_steps']} Adam steps on z over the same samples, the decoder fixed"
    if steps["weight_steps"]:
        stages += f", then {steps['weight_steps']} on the decoded NBRDF's own weights"
    seconds = refinement["seconds_per_material"]
    per_method = ", ".join(f"{method} {value:.2g} s" for method, value in seconds.items())
    refined = REFINED.get(budget, f"refined ({budget})").capitalize()
    return (f"Two protocols. **Encoder only** (rows without \"refined\"): the paper's protocol, each material encoded "
            f"from {samples} samples and decoded. **{refined}** (budget "
            f"`{budget}`: {stages}): what `frenbrdf reconstruct --refine {budget}` gives a user, "
            f"{np.mean(list(seconds.values())):.2g} s of refinement per material beyond encoding ({per_method}). "
            "Its L_fre is that of the refined NBRDF itself. The \"refined z\" edit rows interpolate the refined "
            "latents of the same pairs"
            + (" (the latents after the latent stage: refined weights have no latent)" if steps["weight_steps"] else "")
            + "; `interpolation.png` stays on the encoder's latents, as the paper edits.")


def markdown_table(summary: dict, n_materials: int, n_edits: int, materials: str = "test materials",
                   refine: str = "none", patterns=()) -> str:
    """The reconstruction and editing table, methods side by side, with the paper's numbers (none for ΔE nor
    the refined rows, nor a further pattern's); ``refine``: the refinement budget that ran, ``patterns``: the
    sampling patterns (:func:`table_rows`)."""
    methods = list(summary)
    header = "| | " + " | ".join(methods) + " | " + " | ".join(f"paper: {m}" for m in PAPER) + " |"
    editing = (f"editing over {n_edits} interpolations (each unordered pair of {materials} at most once, "
               "t ∈ {0.25, 0.5, 0.75})" if n_edits else f"no editing rows (editing interpolates two {materials})")
    lines = [f"Reconstruction on {n_materials} {materials}; {editing}. RMSE, PSNR, SSIM and ΔE over "
             "the lit material pixels of the renders (background excluded); L_fre normalised on the sphere "
             "(docs/method.md §5).", "",
             header, "|---" * (1 + len(methods) + len(PAPER)) + "|"]
    for key, label in table_rows(refine, patterns):
        if key.partition("@")[0] in HIGHLIGHT_KEYS and any(key not in summary[m] for m in methods):
            continue  # a report from before the highlight metrics
        if key.startswith("edit_") and not n_edits:
            continue  # a single material: nothing to interpolate, every value None
        ours = " | ".join(f"{summary[m][key]:.3g}" for m in methods)
        paper = " | ".join(f"{PAPER[m].get(key, '–')}" for m in PAPER)
        lines.append(f"| {label} | {ours} | {paper} |")
    return "\n".join(lines) + "\n"
