"""What frenbrdf may read and where it may write: the checks every command makes first.

Inputs
    :func:`input_file` accepts a regular file only (a folder, a FIFO, a device or a symlink
    loop is named as what it is; a FIFO would block a reader for ever). :func:`checked_npz`
    and :func:`torch_load` open ``.npz`` and torch files without trusting them: the sizes a
    zip archive declares are checked before anything is decompressed, nothing but tensors and
    plain data is unpickled, and no message repeats numpy's or torch's advice to load unsafely.

Outputs follow one rule for every command: :mod:`frenbrdf.io.outputs`.
"""

from __future__ import annotations

import errno
import os
import stat
import zipfile
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
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


@contextmanager
def naming(path: str | os.PathLike) -> Iterator[None]:
    """Names ``path`` in a ValueError raised in the block that does not name it already: what a command finds
    wrong in a file's content (no measured bin, a value out of range) is reported against the file, as a reader's
    own errors are, however deep in the analysis it is found."""
    try:
        yield
    except ValueError as error:
        if os.fspath(path) in str(error):
            raise
        try:
            named = type(error)(f"{os.fspath(path)}: {error}")
        except TypeError:  # a subclass with other arguments (UnicodeDecodeError)
            named = ValueError(f"{os.fspath(path)}: {error}")
        raise named from None


def checked_npz(path: str | os.PathLike, what: str = ".npz file", *, member_bytes: int = NPZ_MEMBER_BYTES,
                members: int = 64) -> dict:
    """The arrays of an ``.npz`` file, read only after the archive's declared sizes were checked.

    Every member must be an ``.npy`` array declaring at most ``member_bytes`` uncompressed (a
    zip bomb declares gigabytes), at most ``members`` of them. Each member's own ``.npy``
    header is read and checked too (``_check_npy_header``) before numpy allocates
    anything: pickled objects are refused, and a shape larger than the member is damage.

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
                with archive.open(info) as member:
                    _check_npy_header(path, what, info, member, member_bytes)
        with np.load(path, allow_pickle=False) as saved:
            return {name: np.asarray(saved[name]) for name in saved.files}
    except ValueError as error:
        if str(path) in str(error):
            raise
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None
    except (OSError, EOFError, zipfile.BadZipFile, KeyError, RuntimeError, NotImplementedError,
            zlib.error) as error:  # NotImplementedError: a compression method zipfile lacks
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None


def _check_npy_header(path: Path, what: str, info: zipfile.ZipInfo, member, member_bytes: int) -> None:
    """Checks the ``.npy`` header of one ``.npz`` member before anything is loaded from it.

    The zip states a member's size, the ``.npy`` header the array's shape and dtype: they are
    written separately, so a file can declare a small member holding an array of 10¹¹ elements
    (which numpy would allocate before it found the data missing). The dtype must hold no Python
    objects (pickles), and the array, counted as at least one byte an element, must fit in
    ``member_bytes`` and in the bytes the member holds.
    """
    import numpy as np
    from numpy.lib import format as npy

    version = npy.read_magic(member)
    readers = {(1, 0): npy.read_array_header_1_0, (2, 0): npy.read_array_header_2_0}
    if version not in readers:
        raise ValueError(f"{path}: {info.filename} is an .npy array of format version {version[0]}.{version[1]}; "
                         "frenbrdf reads versions 1.0 and 2.0")
    shape, _, dtype = readers[version](member)
    if dtype.hasobject:
        raise ValueError(f"{path}: {info.filename} holds pickled Python objects, which frenbrdf never loads "
                         "(they could run code); save plain numeric arrays")
    elements = int(np.prod(shape, dtype=object))  # Python integers: a declared shape cannot overflow
    declared = elements * dtype.itemsize
    held = info.file_size - member.tell()
    if elements * max(dtype.itemsize, 1) > member_bytes:
        raise ValueError(f"{path}: {info.filename} declares an array of shape {shape} ({dtype}, {declared:,} bytes), "
                         f"more than the {member_bytes:,} bytes a {what} may hold")
    if declared > held:
        raise ValueError(f"{path}: {info.filename} declares an array of shape {shape} ({dtype}, {declared:,} bytes), "
                         f"but holds only {held:,} bytes of data (damaged or truncated?)")


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
        loaded = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError:
        raise ValueError(f"{path}: not a {what}: it holds objects other than tensors and plain data, which "
                         "frenbrdf never loads (they could run code)") from None
    except Exception as error:  # torch raises several types for damaged files
        raise ValueError(f"{path}: not a readable {what} ({_safe(error)})") from None
    return _plain_tensors(loaded, path, what)


#: How deep :func:`torch_load` looks into nested containers (the deepest frenbrdf writes is 5: an optimizer's state).
MAX_NESTING = 32


def _plain_tensors(value, path, what: str, where: str = "", depth: int = 0):
    """``value`` with every tensor in it checked to be one frenbrdf can compute with: dense, with its data (not
    torch's ``meta`` device), real; half-precision floats become float32 (exactly), in place in dicts and lists (a
    state dict keeps its type and metadata). Raises ValueError naming the file and where in it the tensor lies."""
    import torch

    if depth > MAX_NESTING:
        raise ValueError(f"{path}: not a {what}: containers nested deeper than {MAX_NESTING} levels at {where}")
    if isinstance(value, (dict, list)):
        for key, item in list(value.items() if isinstance(value, dict) else enumerate(value)):
            value[key] = _plain_tensors(item, path, what, f"{where}[{key!r:.40}]", depth + 1)
        return value
    if isinstance(value, tuple):
        return tuple(_plain_tensors(item, path, what, f"{where}[{i}]", depth + 1) for i, item in enumerate(value))
    if not isinstance(value, torch.Tensor):
        return value
    problem = ("has no data (torch's meta device)" if value.is_meta else
               f"is not dense ({value.layout})" if value.layout != torch.strided else
               f"is {value.dtype}, not real numbers" if value.is_complex() or value.is_quantized else "")
    if problem:
        raise ValueError(f"{path}: not a valid {what}: the tensor at {where or 'its top'} {problem}")
    return value.float() if value.dtype in (torch.float16, torch.bfloat16) else value


def _safe(error: BaseException) -> str:
    """An error's message without advice to load unsafely (numpy's allow_pickle, torch's weights_only)."""
    text = str(error).splitlines()[0] if str(error) else type(error).__name__
    if "object arrays" in text.lower():  # numpy refusing an array of Python objects under allow_pickle=False
        return "it holds pickled Python objects, which frenbrdf never loads"
    if "pickle" in text.lower() or "weights_only" in text:
        return "damaged, or not a file of this kind"
    return text
