"""Opening a run in ParaView or pyvista (docs/results.md): the ``view.py`` script written beside every run's
fields, which pvpython, pvbatch or the ParaView GUI runs, and its pyvista equivalent for notebooks.

``view.py`` needs nothing of fepen (ParaView's own Python runs it): it opens ``fields.xdmf`` with the Xdmf3
reader, warps the projectile by ``displacement_m``, colours it by von Mises stress with a colour bar, draws
the target face (the plane y = 0) and leaves the time controls on the output times; with ``--png`` it
renders one picture offscreen instead.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from fepen.errors import InputError, MachineFault

__all__ = ["VIEW_SCRIPT", "write_view_script", "plot", "show", "render_png", "has_display", "missing_fields",
           "NoDisplay", "ViewerFailed"]

#: what ``fepen view`` without a display says (exit code 2)
NO_DISPLAY = "no display: use --png FILE (an offscreen picture)"


class NoDisplay(InputError):
    """A window was asked for where there is no display (no $DISPLAY or $WAYLAND_DISPLAY on X11/Wayland
    systems): exit code 2, ``--png`` renders offscreen instead."""

    def __init__(self):
        super().__init__("", NO_DISPLAY)

    def __reduce__(self):
        return (type(self), ())


class ViewerFailed(MachineFault):
    """The ParaView GUI exited with a non-zero code or on a signal (its own messages went to the terminal):
    exit code 4, a fault of the machine (its graphics), not of the run."""


def has_display(environ=None, platform: str | None = None) -> bool:
    """Whether a window can open: on Linux and the BSDs (X11, Wayland) only with $DISPLAY or $WAYLAND_DISPLAY;
    elsewhere (macOS, Windows) always.

    Args:
        environ: the environment (default os.environ). platform: sys.platform's value (default this one's).

    Returns:
        True when a GUI can be started.
    """
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if not platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return True
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def missing_fields(out: Path) -> str:
    """Why the directory ``out`` holds no fields.xdmf, in words that fit its run: a rigid run writes none, a
    deformable run with run.fields = false neither, a run that stopped before its first output time none yet.

    Args:
        out: the directory.

    Returns:
        One line naming the directory and the reason.
    """
    from fepen.io import results

    files = results.read(out)
    out = files.out
    fidelity = fields = None
    try:
        summary = files.summary()
        fidelity = summary.get("fidelity") or summary["scene"]["effects"]["fidelity"]
        fields = summary["scene"]["run"]["fields"]
    except (KeyError, TypeError, AttributeError):  # a running or killed run: its scene.toml, whose given keys
        given = files.given_scene()                # are values (the others comments)
        if not given:
            return f"{out} holds no fields.xdmf and no run's summary.json or scene.toml: not a run's results directory"
        fidelity = given.get("effects", {}).get("fidelity")
        fields = given.get("run", {}).get("fields")
    if fidelity == "rigid":
        return (f"{out} is a rigid run, which writes no fields (history.csv and summary.json only); run the scene "
                "with effects.fidelity = 'plastic' or 'elastic' to see the projectile")
    if fields is False:
        return f"{out} holds no fields.xdmf: the run had run.fields = false"
    return f"{out} holds no fields.xdmf yet: the run wrote no output time (run.output_interval) before it stopped"

VIEW_SCRIPT = '''"""This run in ParaView: the projectile warped by its displacement, coloured by von Mises stress, the
target face (y = 0) drawn, the time controls on the output times (written by fepen).

    paraview --script=view.py                                  the GUI
    pvpython view.py --png picture.png [--time T] [--field F]  one picture, offscreen (pvbatch works too)
    fepen view DIR [--png picture.png]                         either of the two
"""
import argparse
import os

from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction, Plane,
                             Render, SaveScreenshot, Show, WarpByVector, Xdmf3ReaderS)

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else {here!r}


def main(png=None, time=None, field="von_mises_Pa"):
    reader = Xdmf3ReaderS(registrationName="fields.xdmf", FileName=[os.path.join(HERE, "fields.xdmf")])
    reader.UpdatePipelineInformation()
    times = list(reader.TimestepValues) or [0.0]
    t = times[-1] if time is None else min(times, key=lambda s: abs(s - time))
    warp = WarpByVector(registrationName="deformed", Input=reader)
    warp.Vectors = ["POINTS", "displacement_m"]
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [1200, 800]  # the screenshot's own size: fonts are not scaled up
    view.OrientationAxesVisibility = 1
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t
    warp.UpdatePipeline(t)
    shown = Show(warp, view)
    fine = reader.GetDataInformation().GetNumberOfCells() > 5000
    shown.SetRepresentationType("Surface" if fine else "Surface With Edges")
    shown.EdgeColor = [0.25, 0.25, 0.25]
    centre = "POINTS" if field in ("displacement_m", "velocity_m_s", "wear_depth_m") else "CELLS"
    shown.ColorArrayName = [centre, field]
    lut = GetColorTransferFunction(field)
    lut.ApplyPreset("Jet", True)
    shown.LookupTable = lut
    shown.RescaleTransferFunctionToDataRange(False, True)
    shown.SetScalarBarVisibility(view, True)
    bar = lut.GetScalarBar(view) if hasattr(lut, "GetScalarBar") else None
    if bar is not None:
        bar.Title = field
        bar.ComponentTitle = ""
        bar.TitleFontSize = 14
        bar.LabelFontSize = 12
        bar.ScalarBarLength = 0.4
        bar.RangeLabelFormat = "%-#.3g"
    (x0, x1, y0, y1, z0, z1) = warp.GetDataInformation().GetBounds()
    half = max(x1 - x0, y1 - y0, z1 - z0)
    face = Plane(registrationName="target face (y = 0)")
    face.Origin = [min(x0, 0.0) - half, 0.0, -half]
    face.Point1 = [max(x1, 0.0) + half, 0.0, -half]
    face.Point2 = [min(x0, 0.0) - half, 0.0, half]
    drawn = Show(face, view)
    drawn.DiffuseColor = [0.6, 0.6, 0.6]
    drawn.Opacity = 0.35
    c = [0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * (z0 + z1)]  # the camera on the projectile, a little
    view.CameraFocalPoint = c                                # from above and aside; the face shows when
    view.CameraPosition = [c[0] + 0.8 * half, c[1] + 0.6 * half, c[2] + 2.3 * half]  # the projectile is near it
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraViewAngle = 30.0
    Render(view)
    if png:
        SaveScreenshot(png, view, ImageResolution=[1200, 800])
    return view


if __name__ != "view":  # run, not imported
    parser = argparse.ArgumentParser(description="this run in ParaView")
    parser.add_argument("--png", help="render one picture to this file and exit")
    parser.add_argument("--time", type=float, help="output time (s); default the last")
    parser.add_argument("--field", default="von_mises_Pa", help="the field to colour by")
    args, _ = parser.parse_known_args()
    main(args.png, args.time, args.field)
'''


def write_view_script(out: Path) -> Path:
    """Write ``view.py`` into the results directory ``out`` (rank 0's business). Returns its path."""
    from fepen.atomic import replacing

    path = Path(out) / "view.py"
    with replacing(path) as tmp:
        tmp.write_text(VIEW_SCRIPT.replace("{here!r}", repr(str(Path(out).resolve()))))
    return path


def show(out: Path, field: str = "von_mises_Pa", time: float | None = None, png: str | Path | None = None) -> None:
    """``fepen view``: the run in ``out`` in ParaView on its view.py (written first for a run from before
    view.py), or by pyvista (plot) where ParaView is not installed.

    Args:
        out: results directory with fields.xdmf. field: the field to colour by. time: output time (s); None:
            the last. png: render one picture there, offscreen (pvpython, render_png), instead of opening the
            GUI.

    Raises:
        NoDisplay: a window asked for (no ``png``) without a display (has_display).
        ViewerFailed: the ParaView GUI exited with a non-zero code or on a signal.
    """
    import shutil
    import subprocess

    out = Path(out)
    if not png and not has_display():
        raise NoDisplay()
    script = out / "view.py"
    if not script.is_file():  # a run from before view.py was written
        write_view_script(out)
    if png and shutil.which("pvpython"):
        render_png(script, png, [*(["--time", repr(time)] if time is not None else []), "--field", field])
    elif not png and shutil.which("paraview"):
        code = subprocess.run(["paraview", f"--script={script}"], check=False).returncode
        if code < 0:
            raise ViewerFailed(f"ParaView was killed by signal {-code}")
        if code:
            raise ViewerFailed(f"ParaView exited with code {code} (its messages are above)")
    else:
        plot(out, field, time, png)


def render_png(script: Path, png: str | Path, options=(), tries: int = 3) -> None:
    """pvpython on a run's view.py, offscreen, into ``png``; under xvfb-run (a virtual screen of 24-bit colour
    on a free display number) where it is installed. Two xvfb-run started at once may race for one display:
    up to ``tries`` attempts.

    Raises:
        SimulationError: when ParaView wrote no picture (the end of its stderr).
    """
    import shutil
    import subprocess

    from fepen.errors import SimulationError

    cmd = ["pvpython", "--force-offscreen-rendering", str(script), "--png", str(Path(png).resolve()), *options]
    if shutil.which("xvfb-run"):
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", *cmd]
    for _ in range(tries):
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode == 0 and Path(png).is_file():
            return
    raise SimulationError(f"ParaView could not render {png}: {r.stderr.strip()[-400:]}")


def plot(out: Path, field: str = "von_mises_Pa", time: float | None = None, png: str | Path | None = None):
    """The pyvista equivalent of view.py: the projectile at an output time (the last by default) warped by
    its displacement and coloured by ``field``, with the target face.

    Args:
        out: results directory with fields.xdmf. field: a cell or point field name. time: output time (s).
        png: write the picture there (offscreen) instead of showing it.

    Returns:
        The pyvista Plotter (closed when ``png`` is given).
    """
    import os

    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSOpenGLRenderWindow")
    import numpy as np
    import pyvista as pv

    reader = pv.get_reader(str(Path(out) / "fields.xdmf"))
    times = np.asarray(reader.time_values)
    k = len(times) - 1 if time is None else int(np.argmin(np.abs(times - time)))
    reader.set_active_time_point(k)
    grid = reader.read()
    if isinstance(grid, pv.MultiBlock):
        grid = grid.combine()
    warped = grid.warp_by_vector("displacement_m")
    x0, x1, y0, y1, z0, z1 = warped.bounds
    half = max(x1 - x0, y1 - y0, z1 - z0)
    face = pv.Plane(center=(0.5 * (x0 + x1), 0.0, 0.0), direction=(0.0, 1.0, 0.0), i_size=x1 - x0 + 2 * half,
                    j_size=2 * half)
    plotter = pv.Plotter(off_screen=png is not None, window_size=(1200, 800))
    plotter.add_mesh(warped, scalars=field, cmap="jet", show_edges=True, edge_color="#404040",
                     scalar_bar_args={"title": field})
    plotter.add_mesh(face, color="grey", opacity=0.35)
    plotter.add_text(f"t = {times[k] * 1e6:.1f} us", font_size=10)
    plotter.view_xy()
    plotter.camera.azimuth = 20
    plotter.camera.elevation = 15
    if png is not None:
        from fepen.atomic import replacing

        with replacing(png, ".png") as tmp:
            plotter.screenshot(str(tmp))
        plotter.close()
    else:
        plotter.show()
    return plotter
