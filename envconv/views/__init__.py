"""Ways to look at a map: previews and contact sheets (:mod:`~envconv.views.preview`), the
WebGL viewer page (:mod:`~envconv.views.viewer`), the analytic test pattern
(:mod:`~envconv.views.pattern`, with its bitmap font :mod:`~envconv.views.font`) and the facts
``envconv info`` prints (:mod:`~envconv.views.info`).

The package imports nothing itself: a submodule loads on first use.
"""

from ..lazy import package_getattr

__all__: list[str] = []

__getattr__ = package_getattr(__name__)
