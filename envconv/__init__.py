"""envconv: convert HDR environment maps between layouts, correctly and fast.

>>> import envconv
>>> sky = envconv.read("sky.exr")                       # doctest: +SKIP
>>> cube = envconv.convert(sky, to="cube-vcross", size=512)  # doctest: +SKIP
>>> envconv.write(cube, "sky_cross.exr")                 # doctest: +SKIP

``import envconv`` is cheap: ``EnvMap``, ``read``, ``write``, ``convert`` and the submodules
load on first use, so that a command imports only what it uses.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from .errors import ColorError, EnvconvError, ImageIOError, LayoutError, UsageError

__version__ = "0.1.0"

__all__ = [
    "EnvMap",
    "read",
    "write",
    "convert",
    "EnvconvError",
    "LayoutError",
    "ImageIOError",
    "ColorError",
    "UsageError",
    "__version__",
]

#: Public names loaded on first use, and the module each comes from.
_LAZY = {"EnvMap": ".envmap", "read": ".io", "write": ".io", "convert": ".resample"}

if TYPE_CHECKING:  # pragma: no cover
    from .envmap import EnvMap
    from .io import read, write
    from .resample import convert


def __getattr__(name: str):
    """Load ``EnvMap``, ``read``, ``write``, ``convert`` or a submodule on first use."""
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    elif not name.startswith("__"):
        try:
            value = importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
