"""``envconv layouts``: list the layouts."""

from __future__ import annotations

from .main import cli
from .messages import echo_result

__all__ = ["layouts_command"]


@cli.command("layouts")
def layouts_command():
    """List every layout with a one-line description, the world axis each cube face holds
    (and its turn), then the skybox face sets.

    A face set is how a game or engine names and turns the six files of a cube-faces map
    (--in-convention / --out-convention NAME; draw one with
    envconv pattern 'sky_{face}.png' --to cube-faces --out-convention NAME).

    \b
    Example:
      envconv layouts
    """
    from ..layouts import ALIASES, FAMILIES, LAYOUTS
    from ..layouts.facesets import FACE_SETS
    from ..layouts.geometry import face_axes

    width = max(len(name) for name in LAYOUTS)
    for name, layout in LAYOUTS.items():
        aliases = [alias for alias, target in ALIASES.items() if target == name]
        also = f" (also {', '.join(aliases)})" if aliases else ""
        echo_result(f"{name:<{width}}  {layout.description}{also}")
    echo_result("")
    echo_result("world axis at the centre of each cube face (px..nz: the GL faces +X_c..-Z_c of")
    echo_result("c = (-x, y, z), each an unmirrored view from inside, so px holds world -X):")
    for name in FAMILIES["cubemap"]:
        faces = "  ".join(f"{face} {axis}" + (" (turned 180 degrees)" if turns else "")
                          for face, axis, turns in face_axes(name))  # fmt: skip
        echo_result(f"{name:<{width}}  {faces}")
    echo_result("")
    echo_result("face sets of cube-faces (--in-convention / --out-convention NAME):")
    width = max(len(name) for name in FACE_SETS)
    files = {name: " ".join(s.order()) for name, s in FACE_SETS.items()}
    fwidth = max(len(text) for text in files.values())
    for name, face_set in FACE_SETS.items():
        also = f" (also {', '.join(face_set.aliases)})" if face_set.aliases else ""
        echo_result(f"{name:<{width}}  {files[name]:<{fwidth}}  {face_set.tool}{also}")
