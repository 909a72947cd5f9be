"""One exception hierarchy for envconv.

Library code raises these; only the CLI turns them into one-line messages and exit codes.
"""

__all__ = ["EnvconvError", "LayoutError", "ImageIOError", "ColorError", "UsageError"]


class EnvconvError(Exception):
    """Base class of every error envconv raises on purpose."""


class LayoutError(EnvconvError):
    """An unknown layout, a size that does not fit a layout, or an undetectable layout."""


class ImageIOError(EnvconvError):
    """A file that is missing, unreadable or unwritable."""


class ColorError(EnvconvError):
    """A bad OpenColorIO config or colour-space name."""


class UsageError(EnvconvError):
    """Options that contradict each other or are out of range."""
