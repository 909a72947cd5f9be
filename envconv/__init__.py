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
import sys

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

#: Modules that moved into subpackages (issue 28), by their old names: ``import
#: envconv.pipeline`` still gives :mod:`envconv.engine.pipeline`, the same module object.
#: ``envconv.resample`` and ``envconv.color`` became packages that look names up in
#: :mod:`envconv.resample.convert` and :mod:`envconv.color.ocio`.
MOVED = {
    "steps": "engine.steps", "_walk": "engine.walk", "pipeline": "engine.pipeline",
    "graph": "engine.graph", "batch": "engine.batch", "workers": "engine.workers",
    "api": "engine.api", "outputs": "engine.outputs", "memory": "engine.memory",
    "interrupt": "engine.interrupt", "sourcemap": "resample.holes",
    "sampling": "resample.options", "mips": "resample.mips", "ibl": "resample.ibl",
    "sh": "resample.harmonics", "kernels": "resample.kernels", "geometry": "layouts.geometry",
    "rotation": "layouts.rotation", "conventions": "layouts.conventions",
    "facesets": "layouts.facesets", "detect": "layouts.detect", "prepare": "color.prepare",
    "quantize": "color.quantize", "preview": "views.preview", "viewer": "views.viewer",
    "font": "views.font", "pattern": "views.pattern", "info": "views.info",
}  # fmt: skip


class _MovedModules:
    """Finder and loader of the old module names in :data:`MOVED`: the import gives the moved
    module itself (its ``__spec__`` kept), registered under both names."""

    @staticmethod
    def find_spec(fullname, path=None, target=None):
        package, _, name = fullname.rpartition(".")
        if package != __name__ or name not in MOVED:
            return None
        from importlib.machinery import ModuleSpec

        return ModuleSpec(fullname, _MovedModules)

    @staticmethod
    def create_module(spec):
        module = importlib.import_module(f"{__name__}.{MOVED[spec.name.rpartition('.')[2]]}")
        spec.loader_state = module.__spec__  # the import system overwrites __spec__ next
        return module

    @staticmethod
    def exec_module(module):
        module.__spec__ = module.__spec__.loader_state


sys.meta_path.append(_MovedModules)

#: Public names loaded on first use, and the module each comes from.
_LAZY = {"EnvMap": ".envmap", "read": ".io", "write": ".io", "convert": ".resample.convert"}

#: ``typing.TYPE_CHECKING`` without importing typing (7 ms, and the console script's first
#: import: envconv.__main__ takes SIGINT over only once this package has loaded).
TYPE_CHECKING = False
if TYPE_CHECKING:  # pragma: no cover
    from .envmap import EnvMap
    from .io import read, write
    from .resample.convert import convert


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
