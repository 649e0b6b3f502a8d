"""Exceptions raised by frenbrdf."""


class MerlFormatError(ValueError):
    """A file or array does not follow the MERL BRDF format.

    The message names the file and what was wrong: the header dimensions, the size,
    the offset of a non-finite value, or the shape of an array given for writing.
    """


class TrainingDiverged(RuntimeError):
    """A loss term became NaN or infinite; training stopped and the last good checkpoint is kept."""
