"""The envconv command line: thin click commands over the library API."""

from . import compose  # noqa: F401  (registers the chain runner on the group)
from .main import cli, main

__all__ = ["cli", "main"]
