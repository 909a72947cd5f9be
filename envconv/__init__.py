"""envconv: convert HDR environment maps between layouts, correctly and fast.

>>> import envconv
>>> sky = envconv.read("sky.exr")                       # doctest: +SKIP
>>> cube = envconv.convert(sky, to="cube-vcross", size=512)  # doctest: +SKIP
>>> envconv.write(cube, "sky_cross.exr")                 # doctest: +SKIP
"""

__version__ = "0.1.0"

from .envmap import EnvMap
from .errors import ColorError, EnvconvError, ImageIOError, LayoutError, UsageError
from .io import read, write
from .resample import convert

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
