"""What frenbrdf may read and where it may write: the checks every command makes first.

Inputs
    :func:`input_file` accepts a regular file only (a folder, a FIFO, a device or a symlink
    loop is named as what it is; a FIFO would block a reader for ever). :func:`checked_npz`
    and :func:`torch_load` open ``.npz`` and torch files without trusting them: the sizes a
    zip archive declares are checked before anything is decompressed, nothing but tensors and
    plain data is unpickled, and no message repeats numpy's or torch's advice to load unsafely.
Outputs
    :func:`check_output_folder` refuses, before any work, an output folder that is an
    existing file, the folder of an input (or inside it), an unwritable place, or a folder
    that is not empty and was not written by the same command (unless ``overwrite``).
    :func:`replace_folder` puts a finished folder in place in one rename; the hidden
    ``.NAME.partial-PID-…`` folders it stages in are removed on failure, and those of
    processes that died (``kill -9``) are removed by the next writer of ``NAME``.
    :func:`check_output_file` checks a file to be written (its suffix, its folder).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import os
import shutil
import stat
import uuid
import zipfile
from pathlib import Path

#: The most bytes one member of an ``.npz`` file may declare (uncompressed) by default: 2 GiB.
NPZ_MEMBER_BYTES = 1 << 31


def input_file(path: str | os.PathLike, what: str = "file") -> Path:
    """``path`` as a :class:`~pathlib.Path`, checked to be a readable regular file.

    Raises
    ------
    FileNotFoundError
        Nothing is there.
    IsADirectoryError
        A folder.
    ValueError
        A FIFO, socket, device or a symbolic-link loop: not a file to read.
    """
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise FileNotFoundError(errno.ENOENT, f"{what} does not exist", str(path)) from None
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise ValueError(f"{path}: a loop of symbolic links, not a {what}") from None
        raise
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, f"{what} expected, got a folder", str(path))
    if not stat.S_ISREG(mode):
        kind = "a FIFO (named pipe)" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) else "a device"
        raise ValueError(f"{path}: {kind}, not a regular {what}")
    return path


def checked_npz(path: str | os.PathLike, what: str = ".npz file", *, member_bytes: int = NPZ_MEMBER_BYTES,
                members: int = 64) -> dict:
    """The arrays of an ``.npz`` file, read only after the archive's declared sizes were checked.

    Every member must be an ``.npy`` array declaring at most ``member_bytes`` uncompressed (a
    zip bomb declares gigabytes), at most ``members`` of them; pickled objects are refused.

    Raises
    ------
    ValueError
        Not a zip archive, damaged, too large, or holding something other than arrays; the message
        names the file.
    """
    import numpy as np

    path = input_file(path, what)
    if not zipfile.is_zipfile(path):
        raise ValueError(f"{path}: not a readable {what} (not a zip archive of .npy arrays; damaged or truncated?)")
    try:
        with zipfile.ZipFile(path) as archive:
            infos = archive.infolist()
            if len(infos) > members:
                raise ValueError(f"{path}: {len(infos)} arrays; a {what} holds at most {members}")
            for info in infos:
                if not info.filename.endswith(".npy"):
                    raise ValueError(f"{path}: holds {info.filename!r}, not an .npy array")
                if info.file_size > member_bytes:
                    raise ValueError(f"{path}: {info.filename} declares {info.file_size:,} bytes uncompressed, more "
                                     f"than the {member_bytes:,} a {what} may hold")
        with np.load(path, allow_pickle=False) as saved:
            return {name: np.asarray(saved[name]) for name in saved.files}
    except ValueError as error:
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None
    except (OSError, EOFError, zipfile.BadZipFile, KeyError, RuntimeError) as error:
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None


def torch_load(path: str | os.PathLike, what: str = "torch file"):
    """``torch.load(path, weights_only=True)`` with messages that name the file and never advise loading
    unsafely: a file that is not a torch zip archive (random bytes, truncated) or that holds other objects
    than tensors and plain data is refused as such."""
    import pickle

    import torch

    path = input_file(path, what)
    if not zipfile.is_zipfile(path):
        raise ValueError(f"{path}: not a readable {what} (not a torch zip archive; damaged or truncated?)")
    try:
        return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError:
        raise ValueError(f"{path}: not a {what}: it holds objects other than tensors and plain data, which "
                         "frenbrdf never loads (they could run code)") from None
    except Exception as error:  # torch raises several types for damaged files
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None


def _safe(error: BaseException) -> str:
    """An error's message without advice to load unsafely (numpy's allow_pickle, torch's weights_only)."""
    text = str(error).splitlines()[0] if str(error) else type(error).__name__
    if "pickle" in text.lower() or "weights_only" in text:
        return "damaged, or not a file of this kind"
    return text


def _same_or_inside(path: Path, folder: Path) -> bool:
    try:
        path.relative_to(folder)
    except ValueError:
        return False
    return True


def check_output_folder(out: str | os.PathLike, *, written_by: str, owned: tuple[str, ...] | None = None,
                        inputs: tuple = (), overwrite: bool = False, option: str = "--out") -> Path:
    """Checks where a command may write its folder, before it does any work.

    Parameters
    ----------
    out
        The folder to write (created if missing).
    written_by
        The file that marks a folder as this command's earlier output (``reconstruction.json``,
        ``config.json``); such a folder may be replaced.
    owned
        The names the command writes: a folder holding anything else is the user's (None: any names, in a
        folder holding ``written_by``).
    inputs
        The command's input files and folders: ``out`` may be neither the folder of one nor hold one.
    overwrite
        Replace a non-empty folder that was not written by the command (the user said so).

    Raises
    ------
    ValueError
        An empty name, the folder of an input, an existing file, or a non-empty folder that is not this
        command's output (without ``overwrite``).
    PermissionError
        The folder (or the one it would be created in) is not writable.
    """
    if not str(out).strip():
        raise ValueError(f"{option} is empty; name the folder to write")
    out = Path(out)
    resolved = out.resolve()
    for given in inputs:
        source = Path(given).resolve()
        folder = source if source.is_dir() else source.parent
        if resolved == folder or _same_or_inside(source, resolved):
            raise ValueError(f"{option} {out} is the folder of the input {given} (or holds it); write the results "
                             "to a folder of their own")
    if out.exists() and not out.is_dir():
        raise ValueError(f"{option} {out} exists and is not a folder")
    if out.is_dir():
        present = {entry.name for entry in out.iterdir() if not entry.name.startswith(".")}
        ours = written_by in present and (owned is None or present <= set(owned) | {written_by})
        if present and not ours and not overwrite:
            if written_by not in present:
                why = f"no {written_by}"
            else:
                others = sorted(present - set(owned) - {written_by})
                why = f"it holds files this command does not write: {', '.join(others)}"
            raise ValueError(f"{option} {out} is not empty and was not written by this command ({why}); "
                             "choose another folder, or pass --overwrite to replace it")
        _check_writable(out, option)
    else:
        parent = next(p for p in (resolved, *resolved.parents) if p.exists())
        if not parent.is_dir():
            raise ValueError(f"{option} {out}: {parent} is not a folder")
        _check_writable(parent, option)
    return out


def _check_writable(folder: Path, option: str) -> None:
    if not os.access(folder, os.W_OK | os.X_OK):
        raise PermissionError(errno.EACCES, f"{option}: cannot write in this folder", str(folder))


def check_output_file(path: str | os.PathLike, suffixes: tuple[str, ...], option: str = "--out", *,
                      overwrite: bool) -> Path:
    """Checks a file to be written, before any work: its suffix is one of ``suffixes`` (writers pick the
    format from it), it is not a folder, its folder exists (or can be created) and is writable, and, unless
    ``overwrite``, no file is there already (a command replaces a user's file only when asked)."""
    text = os.fspath(path)
    path = Path(text)
    if not text.strip() or text.endswith(os.sep) or path.is_dir():
        raise ValueError(f"{option} {text!r} is a folder or empty; name the {suffixes[0]} file to write")
    if path.suffix.lower() not in suffixes:
        raise ValueError(f"{option} {text}: the file name must end in {' or '.join(suffixes)}")
    parent = next(p for p in (path.resolve().parent, *path.resolve().parents) if p.exists())
    if not parent.is_dir():
        raise ValueError(f"{option} {text}: {parent} is not a folder")
    _check_writable(parent, option)
    if not overwrite and (path.exists() or path.is_symlink()):
        raise FileExistsError(f"{option} {text} exists; pass --overwrite to replace it")
    return path


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # another user's process
    return True


def staging_folder(out: Path) -> Path:
    """A new hidden folder beside ``out`` to write into (``.NAME.partial-PID-XXXXXXXX``); stale ones left by
    processes that died are removed first."""
    out.parent.mkdir(parents=True, exist_ok=True)
    prefix = f".{out.name}.partial-"
    for stale in out.parent.glob(f"{prefix}*"):
        pid = stale.name[len(prefix):].split("-")[0]
        if pid.isdigit() and int(pid) != os.getpid() and not _alive(int(pid)):
            shutil.rmtree(stale, ignore_errors=True)
    staging = out.parent / f"{prefix}{os.getpid()}-{uuid.uuid4().hex[:8]}"
    staging.mkdir()
    return staging


_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Swaps two paths in one atomic rename (Linux ``renameat2(RENAME_EXCHANGE)``); False where unsupported."""
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    at_fdcwd = -100
    if renameat2(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def replace_folder(staging: Path, out: Path) -> None:
    """Puts the finished folder ``staging`` at ``out`` in one rename, replacing an earlier ``out`` whole:
    readers see the old folder or the new one, never a mix. The old one ends in ``staging``'s name and is
    removed; ``staging`` is removed if anything fails."""
    try:
        if not out.exists():
            os.replace(staging, out)
        elif not _exchange(staging, out):
            # No atomic exchange here: move the old folder aside (one rename), the new one in (another).
            aside = staging.with_name(staging.name + "-old")
            os.replace(out, aside)
            os.replace(staging, out)
            staging = aside
    finally:
        shutil.rmtree(staging, ignore_errors=True)
