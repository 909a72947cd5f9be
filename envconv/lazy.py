"""Attributes of a package loaded on first use: its submodules, and names it forwards to one of
them. ``import envconv`` then costs almost nothing, and ``envconv.resample.kernels`` (or the
name a module had before the regroup, such as ``envconv.resample.default_size``) still works
after ``import envconv``."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable

__all__ = ["package_getattr"]


def package_getattr(package: str, forwarded: Iterable[str] = (),
                    home: str | None = None) -> Callable[[str], object]:  # fmt: skip
    """A module ``__getattr__`` for ``package``: a name in ``forwarded`` comes from submodule
    ``home``; any other name not starting with ``__`` is imported as a submodule, and raises
    AttributeError when there is none."""
    forwarded = frozenset(forwarded)
    namespace = importlib.import_module(package).__dict__

    def __getattr__(name: str):
        if name in forwarded:
            value = getattr(importlib.import_module(f"{package}.{home}"), name)
        elif not name.startswith("__"):
            try:
                value = importlib.import_module(f"{package}.{name}")
            except ModuleNotFoundError as exc:
                if exc.name != f"{package}.{name}":
                    raise
                raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value
        return value

    return __getattr__
