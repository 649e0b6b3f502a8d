"""Exceptions raised by frenbrdf."""


class MerlFormatError(ValueError):
    """A file or array does not follow the MERL BRDF format.

    The message names the file and what was wrong: the header dimensions, the size,
    the offset of a non-finite value, or the shape of an array given for writing.
    """


class BsdfFormatError(ValueError):
    """A file does not follow the RGL material database's ``.bsdf`` (``tensor_file``) format.

    The message names the file and what was wrong: the magic number or version, the field
    and byte offset where the file ends early or a size exceeds it (or exceeds the 256 MiB a
    tensor file may declare), a field's dtype or shape, values that are not reflectance, or
    that the file is spectral (only RGB files are supported).
    """


class TrainingDiverged(RuntimeError):
    """A loss term became NaN or infinite; training stopped and the last good checkpoint is kept."""
