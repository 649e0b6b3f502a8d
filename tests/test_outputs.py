"""The output rule (frenbrdf.io.outputs), held by every command that writes: each command × each state of the
folder (or file) it is pointed at, with every file under the test's folder hashed before and after.

A command may write into a new folder, an empty one, or its own earlier output (recognised by its marker);
a folder holding anything else (hidden entries included) is refused, and with --overwrite those entries are
kept; an input, its folder, a folder holding it, or another command's output is refused even with --overwrite. Files a command did not
write never change, whatever the outcome.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import frenbrdf
from frenbrdf import cli
from frenbrdf.io.outputs import MARKER, OutputFolder

from .conftest import constant_table, random_layers, write_keras_h5

# --- the commands, each with the argv it runs given the inputs folder and the output --------------------------


@dataclass(frozen=True)
class Command:
    name: str
    argv: Callable[[Path, Path], list[str]]  # (the inputs folder, the output) -> the command line
    replaces_own: bool = True  # a rerun into its own output needs no --overwrite (train and additive ones do)
    slow: bool = False  # a success takes more than a few seconds: only the refusals run by default


def _inputs(root: Path) -> Path:
    """The inputs the commands read, in ``root/inputs``: a MERL table, samples, Keras weights, a chart-3 front."""
    folder = root / "inputs"
    if folder.is_dir():
        return folder
    folder.mkdir(parents=True)
    frenbrdf.write_merl(folder / "grey.binary", constant_table(0.1))
    rng = np.random.default_rng(0)
    wi = rng.normal(size=(300, 3))
    wo = rng.normal(size=(300, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]) + 0.2, np.abs(wo[:, 2]) + 0.2
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    rows = np.concatenate([wi, wo, np.full((300, 3), 0.1)], axis=1)
    header = "wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,r,g,b"
    np.savetxt(folder / "samples.csv", rows, delimiter=",", header=header, comments="")
    write_keras_h5(folder / "tiny.h5", random_layers([6, 4, 3]))
    rows = [{"name": "small", "hidden": [8], "latent": 8, "psnr": 30.0, "nbrdf_weights": 91, "bytes_per_material": 364,
             "latent_bytes": 32, "config": {"method": "frenbrdf"}}]
    (folder / "front.json").write_text(json.dumps({"chart": "capacity", "rows": rows}))
    return folder


COMMANDS = [
    Command("reconstruct", lambda i, o: ["reconstruct", str(i / "samples.csv"), "--out", str(o), "--refine", "none",
                                         "--quiet"], slow=True),
    Command("synth", lambda i, o: ["synth", str(o), "--n", "1", "--quiet"]),
    Command("import-nbrdf", lambda i, o: ["import-nbrdf", str(i / "tiny.h5"), str(o), "--quiet"], replaces_own=False),
    Command("fit-nbrdf", lambda i, o: ["fit-nbrdf", str(i / "grey.binary"), "--out", str(o), "--epochs", "1",
                                       "--hidden", "4", "--quiet"], replaces_own=False, slow=True),
    Command("spectrum", lambda i, o: ["spectrum", str(i / "grey.binary"), "--out", str(o), "--lmax", "7"]),
    Command("select", lambda i, o: ["select", "--data", str(i), "--target-psnr", "20", "--front",
                                    str(i / "front.json"), "--out", str(o), "--quiet"]),
    Command("edit", lambda i, o: ["edit", str(i / "samples.csv"), str(i / "samples.csv"), "--out", str(o), "--refine",
                                  "none", "--t", "0.5", "--resolution", "16", "--quiet"], slow=True),
]
FILE_COMMANDS = [
    Command("render", lambda i, o: ["render", str(i / "grey.binary"), "--out", str(o), "--resolution", "16"]),
    Command("convert", lambda i, o: ["convert", str(i / "grey.binary"), str(o)]),
]


def _run(argv: list[str]) -> int:
    try:
        return cli.main(argv)
    except SystemExit as exit:
        return exit.code


def _hashes(root: Path, skip: set[Path] = frozenset()) -> dict[str, str]:
    """Every file under ``root`` (hidden ones and link targets included) by path, as a hash of its bytes."""
    found = {}
    for folder, _, files in os.walk(root, followlinks=False):
        for name in files:
            path = Path(folder) / name
            if path not in skip and path.is_file():
                found[str(path.relative_to(root))] = hashlib.sha256(path.read_bytes()).hexdigest()
    return found


# --- the states of the folder a command is pointed at -------------------------------------------------------------


def _state(state: str, root: Path, inputs: Path, command: Command) -> tuple[Path, str]:
    """Makes ``state`` under ``root``; returns the --out to pass and what must happen: ``ok`` (written),
    ``refused`` (exit 2, nothing changes; --overwrite writes beside the user's entries) or ``never`` (exit 2
    even with --overwrite)."""
    out = root / "out"
    if state == "empty":
        out.mkdir()
    elif state == "hidden-only":
        (out / ".git").mkdir(parents=True)
        (out / ".git" / "HEAD").write_text("ref: refs/heads/main\n")
        return out, "refused"
    elif state == "user-files":
        out.mkdir()
        (out / "notes.txt").write_text("mine")
        (out / "render.png").write_bytes(b"my own picture")  # a name some commands write
        return out, "refused"
    elif state == "own-result":
        assert _run(command.argv(inputs, out)) == 0
    elif state == "other-result":
        other = "spectrum" if command.name != "spectrum" else "synth"
        argv = next(c for c in COMMANDS if c.name == other).argv(inputs, out)
        assert _run(argv) == 0
        return out, "never"  # one command's output a folder: never shared, even when asked
    elif state == "input-folder":  # synth reads nothing: there it is a folder of the user's files
        return inputs, "refused" if command.name == "synth" else "never"
    elif state == "symlink-to-empty":
        (root / "elsewhere").mkdir()
        out.symlink_to(root / "elsewhere", target_is_directory=True)
    elif state == "symlink-to-user":
        (root / "elsewhere").mkdir()
        (root / "elsewhere" / "thesis.tex").write_text("years of work")
        out.symlink_to(root / "elsewhere", target_is_directory=True)
        return out, "refused"
    return out, "ok"


STATES = ["new", "empty", "hidden-only", "user-files", "own-result", "other-result", "input-folder",
          "symlink-to-empty", "symlink-to-user"]


def _cases() -> list:
    """Every command × state; a slow command's successful writes (all but the refusals and the hidden-only folder
    written with --overwrite) run under the ``slow`` marker."""
    refusals = ("hidden-only", "user-files", "input-folder", "other-result", "symlink-to-user")
    return [pytest.param(command, state, id=f"{command.name}-{state}",
                         marks=[pytest.mark.slow] if command.slow and state not in refusals else [])
            for command in COMMANDS for state in STATES]


@pytest.mark.parametrize(("command", "state"), _cases())
def test_every_command_keeps_every_file_it_did_not_write(tmp_path, command, state):
    inputs = _inputs(tmp_path)
    out, expected = _state(state, tmp_path, inputs, command)
    earlier = _marked(out)  # its own earlier output: these files may be replaced
    before = _hashes(tmp_path, earlier)
    overwrite = state == "own-result" and not command.replaces_own
    code = _run(command.argv(inputs, out) + (["--overwrite"] if overwrite else []))
    after = _hashes(tmp_path, earlier)
    assert {k: v for k, v in after.items() if k in before} == before, "a file the command did not write changed"
    if expected == "ok":
        assert code == 0
        assert out.is_dir() and (out / MARKER).is_file()
        assert (out.is_symlink()) == state.startswith("symlink")  # a link to a folder stays a link
        return
    assert code == 2
    assert set(after) == set(before), "a refused command wrote something"
    if expected == "refused" and (not command.slow or (state, command.name) == ("hidden-only", "reconstruct")):
        # With --overwrite it writes beside the user's entries, which stay as they were; a user's file at a name
        # the command writes is still refused.
        clash = state == "user-files" and command.name == "reconstruct"
        assert _run(command.argv(inputs, out) + ["--overwrite"]) == (2 if clash else 0)
        after = _hashes(tmp_path, earlier)
        assert {k: v for k, v in after.items() if k in before} == before
    elif expected == "never":  # an input's folder: never, even when asked
        assert _run(command.argv(inputs, out) + ["--overwrite"]) == 2
        assert _hashes(tmp_path, earlier) == before


def _marked(out: Path) -> set[Path]:
    """The files listed by a marker in ``out`` (its own earlier output), whole subtrees for folders."""
    if not (out / MARKER).is_file():
        return set()
    listed = json.loads((out / MARKER).read_text())["entries"]
    found = {out / MARKER}
    for name in listed:
        path = out / name
        found |= {path} | ({p for p in path.rglob("*")} if path.is_dir() else set())
    return found


@pytest.mark.parametrize("command", FILE_COMMANDS, ids=lambda c: c.name)
def test_file_outputs_never_replace_an_input_and_a_user_file_only_when_asked(tmp_path, command):
    inputs = _inputs(tmp_path)
    suffix = ".png" if command.name == "render" else ".binary"
    target = tmp_path / f"result{suffix}"
    assert _run(command.argv(inputs, target)) == 0  # new
    target.write_bytes(b"the user's file")
    before = _hashes(tmp_path)
    assert _run(command.argv(inputs, target)) == 2  # exists: refused
    assert _hashes(tmp_path) == before
    assert _run(command.argv(inputs, target) + ["--overwrite"]) == 0  # the user asked
    assert target.read_bytes() != b"the user's file"
    if command.name == "convert":  # its input as output, directly or through a link: never
        link = tmp_path / "link.binary"
        link.symlink_to(inputs / "grey.binary")
        before = _hashes(tmp_path)
        for output in (inputs / "grey.binary", link):
            assert _run(["convert", str(inputs / "grey.binary"), str(output), "--overwrite"]) == 2
        assert _hashes(tmp_path) == before


def test_fit_nbrdf_merl_never_replaces_its_input(tmp_path):
    inputs = _inputs(tmp_path)
    before = _hashes(tmp_path)
    argv = ["fit-nbrdf", str(inputs / "grey.binary"), "--out", str(inputs), "--merl", "--epochs", "1", "--overwrite",
            "--quiet"]
    assert _run(argv) == 2
    assert _hashes(tmp_path) == before


def test_import_grows_its_folder_and_replaces_its_own_file_only_when_asked(tmp_path):
    inputs = _inputs(tmp_path)
    out = tmp_path / "imported"
    write_keras_h5(inputs / "other.h5", random_layers([6, 4, 3], seed=1))
    assert _run(["import-nbrdf", str(inputs / "tiny.h5"), str(out), "--quiet"]) == 0
    assert _run(["import-nbrdf", str(inputs / "other.h5"), str(out), "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "other.binary", "tiny.binary"]
    assert _run(["import-nbrdf", str(inputs / "tiny.h5"), str(out), "--quiet"]) == 2  # its own file: when asked
    assert _run(["import-nbrdf", str(inputs / "tiny.h5"), str(out), "--quiet", "--overwrite"]) == 0


def test_a_forged_marker_cannot_make_a_command_delete_outside_its_folder(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    out = tmp_path / "out"
    out.mkdir()
    (out / MARKER).write_text(json.dumps({"command": "synth", "entries": ["../victim.txt", "/etc"]}))
    with pytest.raises(ValueError, match="cannot read"):  # not a marker of ours, and not to be replaced
        OutputFolder.claim(out, command="synth", overwrite=True)
    assert victim.read_text() == "keep me"


def test_entries_that_appear_while_a_command_runs_stay_the_users(tmp_path):
    """A long run (begin … finish) records only what it declared: a `.git` or notes made in its folder meanwhile are
    the user's, so a rerun, even with --overwrite, keeps them."""
    out = tmp_path / "run"
    folder = OutputFolder.claim(out, command="train")
    folder.begin(["last.pt"])
    (out / "last.pt").write_text("an epoch")
    (out / ".git").mkdir()
    (out / ".git" / "HEAD").write_text("ref: refs/heads/main")
    (out / "notes.md").write_text("mine")
    folder.finish()
    assert json.loads((out / MARKER).read_text())["entries"] == ["last.pt"]
    again = OutputFolder.claim(out, command="train", overwrite=True)
    assert again.others == {".git", "notes.md"}
    again.begin(["last.pt"])
    again.finish()
    assert (out / ".git" / "HEAD").read_text() == "ref: refs/heads/main" and (out / "notes.md").read_text() == "mine"


def test_a_staged_write_refuses_a_name_the_user_took_meanwhile_and_records_only_its_own(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    folder = OutputFolder.claim(out, command="evaluate")
    with pytest.raises(ValueError, match="holds report.md, which this command would replace"):
        with folder.staged() as staging:
            (staging / "report.md").write_text("the command's")
            (out / "report.md").write_text("the user's")  # made while the command ran
    assert (out / "report.md").read_text() == "the user's"
    folder = OutputFolder.claim(out, command="evaluate", overwrite=True)
    with folder.staged() as staging:
        (staging / "results.json").write_text("{}")
        (out / "notes.md").write_text("mine")
    assert json.loads((out / MARKER).read_text())["entries"] == ["results.json"]
    with folder.staged() as staging:  # a second write of the same run replaces its own entry only
        (staging / "results.json").write_text("[]")
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "notes.md", "report.md", "results.json"]


def test_a_folder_the_command_wrote_is_not_replaced_nor_removed_once_the_user_added_to_it(tmp_path):
    """Inside its own subfolders too a command replaces only what it wrote: a note left in `seed-1/` stops the
    rerun that would replace that folder (staged) or remove it (begin), before anything changes."""
    out = tmp_path / "evaluation"
    with OutputFolder.claim(out, command="evaluate").staged() as staging:
        (staging / "seed-1").mkdir()
        (staging / "seed-1" / "evaluation.json").write_text("{}")
    assert json.loads((out / MARKER).read_text())["contents"] == {"seed-1": ["evaluation.json"]}
    (out / "seed-1" / "my-notes.txt").write_text("mine")
    for names in (["seed-1"], ["seed-2"]):  # seed-1 replaced, or removed as the rerun no longer writes it
        with pytest.raises(ValueError, match=r"seed-1/ holds my-notes.txt, which this command did not write"):
            with OutputFolder.claim(out, command="evaluate", overwrite=True).staged() as staging:
                for name in names:
                    (staging / name).mkdir()
        assert (out / "seed-1" / "my-notes.txt").read_text() == "mine"
        assert sorted(p.name for p in out.iterdir()) == [MARKER, "seed-1"]
    demo = tmp_path / "demo"
    folder = OutputFolder.claim(demo, command="demo")
    folder.begin(["runs"])
    (demo / "runs" / "run-0").mkdir(parents=True)
    (demo / "runs" / "run-0" / "last.pt").write_text("weights")
    folder.finish()
    (demo / "runs" / "run-0" / "notes.md").write_text("mine")
    with pytest.raises(ValueError, match=r"runs/ holds run-0/notes.md"):
        OutputFolder.claim(demo, command="demo", overwrite=True).begin(["runs"])
    assert (demo / "runs" / "run-0" / "notes.md").read_text() == "mine"
    (demo / "runs" / "run-0" / "notes.md").unlink()  # as the command left it: replaced as before
    OutputFolder.claim(demo, command="demo").begin(["runs"])
    assert not (demo / "runs").exists()


def test_a_marker_whose_record_of_contents_is_malformed_is_not_ours(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / MARKER).write_text(json.dumps({"command": "evaluate", "entries": ["a"], "contents": {"a": "b"}}))
    with pytest.raises(ValueError, match="cannot read"):
        OutputFolder.claim(out, command="evaluate", overwrite=True)


def test_out_dot_writes_into_the_current_folder(tmp_path, monkeypatch):
    """``--out .`` (the folder itself is never renamed, so no 'Device or resource busy')."""
    inputs = _inputs(tmp_path)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert _run(["spectrum", str(inputs / "grey.binary"), "--out", ".", "--lmax", "7"]) == 0
    assert (work / "spectrum.json").is_file()


def test_a_dead_writers_staging_folder_is_cleaned_and_a_live_ones_refused(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / ".frenbrdf-partial-999999999-deadbeef").mkdir()  # no such process
    claimed = OutputFolder.claim(out, command="synth")
    assert claimed.others == frozenset() and not (out / ".frenbrdf-partial-999999999-deadbeef").exists()
    (out / f".frenbrdf-partial-{os.getppid()}-cafebabe").mkdir()  # a live process
    with pytest.raises(ValueError, match="another frenbrdf process"):
        OutputFolder.claim(out, command="synth")


# --- the long commands: train, evaluate, demo refuse before any work --------------------------------------------

LONG = {
    "train": lambda source, out: ["train", "--data", str(source), "--out", str(out), "--epochs", "1", "--quiet"],
    "evaluate": lambda source, out: ["evaluate", str(source), "--out", str(out), "--quiet"],
    "demo": lambda source, out: ["demo", "--data", str(source), "--out", str(out), "--epochs", "1", "--quiet"],
}


@pytest.mark.parametrize("state", ["hidden-only", "user-files", "other-result", "symlink-to-user", "input-folder"])
@pytest.mark.parametrize("name", sorted(LONG))
def test_the_long_commands_refuse_a_folder_that_is_not_theirs_before_any_work(tmp_path, name, state):
    """Their successful writes are tested where they run (tests/test_training.py, test_evaluation.py, test_inputs.py);
    here every refusal, which comes before any training or rendering."""
    source = tmp_path / ("run" if name == "evaluate" else "data")  # what the command reads: a run or a data folder
    source.mkdir()
    frenbrdf.write_merl(source / "grey.binary", constant_table(0.1))
    inputs = _inputs(tmp_path)
    if state == "input-folder":
        out = source
    else:
        out, _ = _state(state, tmp_path, inputs, COMMANDS[1])  # synth: its other-result is spectrum's output
    before = _hashes(tmp_path)
    assert _run(LONG[name](source, out)) == 2
    if state in ("input-folder", "other-result"):  # never, even when asked
        assert _run(LONG[name](source, out) + ["--overwrite"]) == 2
    assert _hashes(tmp_path) == before
