"""Installed distributions' versions without importing ``importlib.metadata`` (0.02 s).

:func:`installed_version` reads the version from the ``NAME-VERSION.dist-info`` directory that
``importlib.metadata`` would find first on ``sys.path``, and asks ``importlib.metadata`` only
when there is no such directory (an egg, a zip, a custom finder).
"""

from __future__ import annotations

import os
import re
import sys

__all__ = ["installed_version"]


def _normalized(name: str) -> str:
    return re.sub(r"[-_.]+", "_", name).lower()


def installed_version(distribution: str) -> str | None:
    """The version of ``distribution`` as installed, or None when it is not installed."""
    wanted = _normalized(distribution)
    for entry in sys.path:
        try:
            names = os.listdir(entry or ".")
        except OSError:  # not a directory (a zip), or gone
            continue
        for name in names:
            if name.endswith(".dist-info"):
                dist, _, version = name[: -len(".dist-info")].partition("-")
                if version and _normalized(dist) == wanted:
                    return version
    from importlib import metadata

    try:
        return metadata.version(distribution)
    except metadata.PackageNotFoundError:
        return None
