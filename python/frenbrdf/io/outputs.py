"""Where a command may write: one rule for every command that writes a folder or a file.

A command writes its folder into

- a new folder (created),
- an empty one (hidden entries such as ``.git`` count: a folder holding them is not empty),
- or its own earlier output, recognised by the marker it left there (:data:`MARKER`: the command's
  name and the entries it wrote), never by file names.

Anything else in the folder is the user's. Without ``overwrite`` a folder holding such entries is
refused; with ``overwrite`` the command writes beside them, and still never replaces or deletes one:
``overwrite`` lets a command replace only what a run of the same command wrote. The same holds inside
the folders a command wrote (``seed-1/``, ``runs/``): the marker lists what each held when the command
finished, and a folder that has gained anything since is neither replaced nor removed (the command
stops, naming what it found). A folder holds one
command's output: another command's (or a marker that cannot be read) is refused even with ``overwrite``.
An output is never one of the command's inputs, the folder of an input, nor a folder holding one.

Two ways to write, both through :class:`OutputFolder`:

``with folder.staged() as staging:``
    Everything is written into a hidden folder first and moved in when complete (a new folder appears
    whole, in one rename; in an existing one each entry is replaced in one rename).
``folder.begin()`` … ``folder.finish()``
    For long work that writes as it goes (training, evaluation): the marker is written first, so a
    run that dies half-way still leaves a folder the same command may replace.

A single output file (a PNG, a converted table) is checked by :func:`check_output_file`: never an
input, and an existing file is replaced only with ``overwrite``.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import uuid
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from .atomic import raise_naming, save_json, sync, sync_entries

#: The hidden file that marks a folder as a command's output and lists what it wrote.
MARKER = ".frenbrdf-output.json"
#: Hidden staging folders: ``.frenbrdf-partial-PID-XXXXXXXX`` (inside the output, or beside a new one).
STAGING_PREFIX = ".frenbrdf-partial-"
#: The largest marker read (a marker lists names; a bigger file is not one of ours).
MARKER_BYTES = 1 << 22
#: The most paths recorded of one folder the command wrote; a larger one goes unrecorded (replaced as a whole).
CONTENTS_PATHS = 20_000


def _option_error(option: str, out, message: str) -> ValueError:
    return ValueError(f"{option} {out}: {message}")


def _inside(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def check_not_input(target: Path, inputs: Iterable, *, option: str, out) -> None:
    """Refuses an output ``target`` (resolved) that is an input, the folder of an input file, or holds an input."""
    for given in inputs:
        source = Path(given).resolve()
        folder = source if source.is_dir() else source.parent
        if target == source or target == folder or _inside(source, target):
            raise _option_error(option, out, f"is the input {given}, its folder, or holds it; write the results "
                                "to a folder of their own")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process
    return True


def _staging_pid(name: str) -> int | None:
    """The process id in a staging folder's name (``.frenbrdf-partial-PID-…`` or ``.NAME.partial-PID-…``)."""
    rest = name[len(STAGING_PREFIX):] if name.startswith(STAGING_PREFIX) else name.partition(".partial-")[2]
    pid = rest.split("-")[0]
    return int(pid) if pid.isdigit() else None


def _read_marker(folder: Path) -> dict | None:
    """The marker of ``folder`` if it is a well-formed one, else None (then it is the user's file like any other)."""
    path = folder / MARKER
    try:
        if not path.is_file() or path.is_symlink() or path.stat().st_size > MARKER_BYTES:
            return None
        marker = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError):
        return None
    if not isinstance(marker, dict) or not isinstance(marker.get("command"), str):
        return None
    entries = marker.get("entries")
    # Plain names only: a forged marker must not make a command delete anything outside its folder.
    if not isinstance(entries, list) or not all(isinstance(e, str) and _plain_name(e) for e in entries):
        return None
    contents = marker.get("contents", {})
    if not isinstance(contents, dict) or not all(
            isinstance(name, str) and isinstance(paths, list) and all(isinstance(p, str) for p in paths)
            for name, paths in contents.items()):
        return None
    return marker


def _plain_name(name: str) -> bool:
    return bool(name) and name not in (".", "..", MARKER) and "/" not in name and "\0" not in name \
        and os.sep not in name


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    else:
        path.unlink(missing_ok=True)


def _is_folder(path: Path) -> bool:
    return path.is_dir() and not path.is_symlink()


def _contents(folder: Path) -> list[str] | None:
    """Every path under ``folder`` (relative, links not followed), or None past :data:`CONTENTS_PATHS`."""
    found = []
    for root, dirs, files in os.walk(folder):
        found += [os.path.relpath(os.path.join(root, name), folder) for name in dirs + files]
        if len(found) > CONTENTS_PATHS:
            return None
    return sorted(found)


@dataclass
class OutputFolder:
    """A folder a command has been allowed to write (:meth:`claim`), and what in it is whose.

    Attributes
    ----------
    path
        The folder as the user named it (for messages).
    target
        The folder resolved (symbolic links followed): where entries are written. The folder itself is never
        renamed or replaced, so ``--out .``, a mount point or a link to a folder work like any other.
    command
        The command writing (its name goes into the marker).
    earlier
        Entries a run of the same command wrote here (listed by its marker; this run's too, once written):
        these may be replaced.
    others
        Every other entry: the user's, never replaced nor deleted.
    additive
        Entries of earlier runs that this run does not write stay (a folder of fits that grows); otherwise an
        earlier run's entries are removed, so the folder holds one run's output.
    overwrite
        The user allowed writing beside their entries (and, when ``additive``, replacing an earlier run's entry).
    option
        The option that named the folder, for messages.
    contents
        What each folder among ``earlier`` held when the command wrote it (from the marker): a folder that holds
        more now is not replaced nor removed. A folder without a record (an older marker, a run that died
        before :meth:`finish`) is the command's as a whole.
    """

    path: Path
    target: Path
    command: str
    earlier: frozenset[str]
    others: frozenset[str]
    additive: bool
    overwrite: bool
    option: str = "--out"
    contents: dict[str, list[str]] = field(default_factory=dict)

    @classmethod
    def claim(cls, out: str | os.PathLike, *, command: str, inputs: Iterable = (), overwrite: bool = False,
              option: str = "--out", additive: bool = False) -> OutputFolder:
        """Checks, before any work, that ``command`` may write the folder ``out``; see the module docstring.

        Raises
        ------
        ValueError
            An empty name, an existing file, an input or an input's folder, or a folder holding the user's
            entries (without ``overwrite``); the message names them.
        PermissionError
            The folder, or the one it would be created in, is not writable.
        """
        if not str(out).strip():
            raise ValueError(f"{option} is empty; name the folder to write")
        path = Path(out)
        target = path.resolve()
        check_not_input(target, inputs, option=option, out=out)
        if path.exists() and not path.is_dir():
            raise _option_error(option, out, "exists and is not a folder")
        earlier: frozenset[str] = frozenset()
        others: frozenset[str] = frozenset()
        contents: dict[str, list[str]] = {}
        if target.is_dir():
            entries = {entry.name for entry in target.iterdir()} - _staging_entries(target)
            marker = _read_marker(target)
            if marker is not None and marker["command"] == command:
                earlier = frozenset(set(marker["entries"]) & entries)
                contents = {name: paths for name, paths in marker.get("contents", {}).items() if name in earlier}
                entries -= earlier | {MARKER}
            others = frozenset(entries)
            if MARKER in others:  # one marker a folder: another command's output is never shared, even when asked
                whose = f"frenbrdf {marker['command']}'s output" if marker else f"a {MARKER} frenbrdf cannot read"
                raise _option_error(option, out, f"holds {whose}; choose a new or empty folder")
            if others and not overwrite:
                shown = ", ".join(sorted(others)[:4]) + (" …" if len(others) > 4 else "")
                raise _option_error(option, out, f"holds {shown} (not this command's earlier output); choose a new "
                                    "or empty folder, or pass --overwrite to write beside those (they are kept)")
            _check_writable(target, option)
        else:
            parent = next(p for p in target.parents if p.exists())
            if not parent.is_dir():
                raise _option_error(option, out, f"{parent} is not a folder")
            _check_writable(parent, option)
        return cls(path, target, command, earlier, others, additive, overwrite, option, contents)

    def check_names(self, names: Iterable[str]) -> None:
        """Refuses, before any work, names this run would write that are the user's entries, or (``additive``
        without ``overwrite``) an earlier run's."""
        names = set(names)
        if clash := sorted(names & self.others):
            raise _option_error(self.option, self.path, f"holds {', '.join(clash[:4])}, which this command would "
                                "replace and did not write; move it, or choose another folder")
        if self.additive and not self.overwrite and (again := sorted(names & self.earlier)):
            raise _option_error(self.option, self.path, f"already holds {', '.join(again[:4])}; pass --overwrite to "
                                "replace it")

    def begin(self, names: Iterable[str] = (), *, keep: Iterable[str] = ()) -> Path:
        """Makes the folder ready for writing in place and returns it: the marker first, listing ``names`` (the
        entries this run will write, checked by :meth:`check_names`), so the folder stays this command's if the
        run dies; then an earlier run's entries are removed, but for those in ``keep`` (work a rerun reuses)
        and all of them when ``additive``."""
        names = set(names)
        self._refresh_others()
        self.check_names(names)
        removed = set() if self.additive else self.earlier - set(keep)
        self._check_unchanged(removed | (names & self.earlier) - set(keep))
        self.target.mkdir(parents=True, exist_ok=True)
        # What this run may change goes unrecorded until finish() records it again.
        self.contents = {}
        self._write_marker(self.earlier | names)
        for name in removed:
            _remove(self.target / name)
        self.earlier = frozenset(names | (self.earlier if self.additive else self.earlier & set(keep)))
        return self.target

    def finish(self) -> None:
        """Records which of this run's entries (:meth:`begin`'s names, an earlier run's kept ones) the folder now
        holds. Only those: an entry that appeared any other way while the command ran (a user's ``.git``, their
        notes) is the user's, never recorded, so no later run removes it."""
        self.earlier = frozenset(self.earlier & self._listing())
        self._record_contents(self.earlier)
        self._write_marker(self.earlier)

    def _listing(self) -> set[str]:
        return {entry.name for entry in self.target.iterdir()} - _staging_entries(self.target) - {MARKER}

    def _refresh_others(self) -> None:
        """Counts as the user's every entry that appeared since the claim and that no run of this command wrote:
        a long command finds the folder as the user has left it, not as it was when the command started."""
        if self.target.is_dir():
            self.others = frozenset(self.others | (self._listing() - self.earlier))

    @contextmanager
    def staged(self) -> Iterator[Path]:
        """A hidden folder to write everything into; when the block ends without error its entries are put
        in place (a new folder in one rename, else entry by entry, each in one rename) and the marker written.
        On error nothing in the output changes and the hidden folder is removed."""
        new = not self.target.exists()
        parent = self.target.parent if new else self.target
        parent.mkdir(parents=True, exist_ok=True)
        staging = parent / f"{STAGING_PREFIX}{os.getpid()}-{uuid.uuid4().hex[:8]}"
        staging.mkdir()
        try:
            yield staging
            names = {entry.name for entry in staging.iterdir()}
            self._refresh_others()
            self.check_names(names)
            if new:
                self.contents = {name: paths for name in names
                                 if _is_folder(staging / name) and (paths := _contents(staging / name)) is not None}
                self.earlier = frozenset(names)
                save_json(staging / MARKER, self._marker(self.earlier))
                sync(staging)
                os.replace(staging, self.target)
                sync_entries(self.target.parent)
                return
            removed = set() if self.additive else self.earlier - names
            self._check_unchanged(removed | (names & self.earlier))
            self._write_marker(self.earlier | names)
            sync(staging)
            for name in names:
                destination = self.target / name
                if _is_folder(destination):
                    os.replace(destination, staging / f".old-{name}")  # a folder cannot be renamed over
                os.replace(staging / name, destination)
            sync_entries(self.target)
            for name in removed:
                _remove(self.target / name)
            self.earlier = frozenset(names | (self.earlier if self.additive else set()))
            self._record_contents(names)
            self._write_marker(self.earlier)
        except (OSError, ValueError) as error:  # a message names the output, never the hidden staging folder
            raise_naming(error, staging, self.path)
        finally:
            shutil.rmtree(staging, ignore_errors=True)

    def _check_unchanged(self, names: Iterable[str]) -> None:
        """Refuses, before anything is replaced or removed, to touch a folder among ``names`` that holds a path
        it did not hold when this command wrote it."""
        for name in sorted(names):
            recorded = self.contents.get(name)
            if recorded is None or not _is_folder(self.target / name):
                continue
            now = _contents(self.target / name)
            added = sorted(set(now) - set(recorded)) if now is not None else ["more than the command wrote"]
            if added:
                raise _option_error(self.option, self.path, f"{name}/ holds {', '.join(added[:3])}, which this command "
                                    "did not write; move it out, or choose another folder")

    def _record_contents(self, names: Iterable[str]) -> None:
        for name in names:
            if _is_folder(self.target / name) and (paths := _contents(self.target / name)) is not None:
                self.contents[name] = paths
            else:
                self.contents.pop(name, None)

    def _marker(self, entries: Iterable[str]) -> dict:
        entries = sorted(entries)
        contents = {name: self.contents[name] for name in entries if name in self.contents}
        return {"command": self.command, "entries": entries} | ({"contents": contents} if contents else {})

    def _write_marker(self, entries: Iterable[str]) -> None:
        save_json(self.target / MARKER, self._marker(entries))


def _staging_entries(folder: Path) -> set[str]:
    """Staging folders in ``folder``: those of processes that died are removed; a live writer's is refused."""
    found = set()
    for entry in folder.iterdir():
        if not entry.name.startswith(STAGING_PREFIX):
            continue
        pid = _staging_pid(entry.name)
        if pid is not None and pid != os.getpid() and _alive(pid):
            raise ValueError(f"{folder}: another frenbrdf process ({pid}) is writing here; wait for it to end")
        if pid is not None and pid != os.getpid():
            shutil.rmtree(entry, ignore_errors=True)
        found.add(entry.name)
    return found


def _check_writable(folder: Path, option: str) -> None:
    if not os.access(folder, os.W_OK | os.X_OK):
        raise PermissionError(errno.EACCES, f"{option}: cannot write in this folder", str(folder))


def check_output_file(path: str | os.PathLike, suffixes: tuple[str, ...], option: str = "--out", *,
                      overwrite: bool, inputs: Iterable = ()) -> Path:
    """Checks a file to be written, before any work: its suffix is one of ``suffixes`` (writers pick the
    format from it), it is not a folder nor one of ``inputs``, its folder exists (or can be created) and is
    writable, and, unless ``overwrite``, no file is there already (a command replaces a user's file only when
    asked)."""
    text = os.fspath(path)
    path = Path(text)
    if not text.strip() or text.endswith(os.sep) or path.is_dir():
        raise ValueError(f"{option} {text!r} is a folder or empty; name the {suffixes[0]} file to write")
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{option} {text}: the file name must end in {' or '.join(suffixes)}")
    resolved = path.resolve()
    for given in inputs:
        if resolved == Path(given).resolve():
            raise ValueError(f"{option} {text} is the input {given}; write to another file")
    parent = next(p for p in resolved.parents if p.exists())
    if not parent.is_dir():
        raise ValueError(f"{option} {text}: {parent} is not a folder")
    _check_writable(parent, option)
    if path.exists() or path.is_symlink():
        if not (path.is_file() or path.is_symlink()):
            raise ValueError(f"{option} {text} exists and is not a regular file")
        if not overwrite:
            raise FileExistsError(f"{option} {text} exists; pass --overwrite to replace it")
    return path


def check_free_space(folder: Path, needed: int, what: str) -> None:
    """Refuses, before any work, to write ``needed`` bytes (``what``) where the disk has less free."""
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    free = shutil.disk_usage(existing).free
    if needed > free:
        raise OSError(errno.ENOSPC, f"{what} need {needed / 1e9:.1f} GB; {existing} has {free / 1e9:.1f} GB free")
