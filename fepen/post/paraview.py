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

__all__ = ["VIEW_SCRIPT", "view_script", "write_view_script", "plot", "show", "render_png", "has_display",
           "missing_fields", "NoDisplay", "ViewerFailed", "field_centres", "field_centre", "field_unit", "run_name",
           "view_title"]

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

#: where an XDMF Attribute's Center puts a field, as ParaView and pyvista name it
CENTRES = {"Node": "POINTS", "Cell": "CELLS"}
#: a field's unit from the end of its name (every field of fepen carries its unit in its name); none: dimensionless
UNITS = (("_m_s", "m/s"), ("_Pa", "Pa"), ("_N", "N"), ("_K", "K"), ("_J", "J"), ("_m", "m"), ("_s", "s"))


def field_centres(out: Path) -> dict[str, str]:
    """The fields of a run's fields.xdmf and where each lives, as the file says (its Attribute elements' Center),
    never from a list of names: a field added to the run is drawn where it is written.

    Args:
        out: the results directory.

    Returns:
        {field name: "POINTS" (Center="Node") or "CELLS" (Center="Cell")}, in the file's order.

    Raises:
        InputError: ("dir") fields.xdmf is not XML (not a file fepen wrote).
    """
    import xml.etree.ElementTree as ET

    path = Path(out) / "fields.xdmf"
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as err:
        raise InputError("dir", f"{path} is not an XDMF file: {err}") from None
    found: dict[str, str] = {}
    for attribute in root.iter("Attribute"):
        centre = CENTRES.get(attribute.get("Center", "Node"))
        if centre is not None:
            found.setdefault(attribute.get("Name"), centre)
    return found


def field_centre(out: Path, field: str, key: str = "--field") -> str:
    """Where ``field`` lives in the run's fields ("POINTS" or "CELLS", field_centres).

    Args:
        out: the results directory. field: the field's name. key: the argument the user gave it by.

    Raises:
        InputError: (key) the run has no such field: one line naming the fields it has.
    """
    centres = field_centres(out)
    if field not in centres:
        fields = f"its fields: {', '.join(centres)}" if centres else "its fields.xdmf holds none"
        raise InputError(key, f"{field!r} is not a field of this run; {fields}")
    return centres[field]


def field_unit(field: str) -> str:
    """A field's unit from the end of its name ("Pa", "m/s", ...; "dimensionless" for peeq, triaxiality, tags)."""
    return next((unit for end, unit in UNITS if field.endswith(end)), "dimensionless")


def run_name(out: Path) -> str:
    """The run's shot and fidelity as the figures' titles name it (fepen.post.figures.run_title), or "" when the
    directory holds no readable scene."""
    from fepen.post.figures import run_title

    try:
        return run_title(out)
    except Exception:  # noqa: BLE001 - a title is not worth failing a picture for
        return ""


def view_title(out: Path, field: str, t: float) -> str:
    """The title of a picture of the run (view.py's ``title``, which ParaView runs without fepen): "FIELD (UNIT) at
    t = T µs — SHOT".

    Args:
        out: the results directory. field: the field drawn. t: the frame's output time (s).

    Returns:
        The title.
    """
    text = f"{field} ({field_unit(field)}) at t = {t * 1e6:.1f} µs"
    name = run_name(out)
    return f"{text} — {name}" if name else text


VIEW_SCRIPT = '''"""This run in ParaView: the projectile warped by its displacement, coloured by von Mises stress, the
target face (y = 0) drawn, the time controls on the output times (written by fepen).

    paraview --script=view.py                                  the GUI
    pvpython view.py --png picture.png [--time T] [--field F]  one picture, offscreen (pvbatch works too)
    fepen view DIR [--png picture.png]                         either of the two
"""
import argparse
import os

from paraview.simple import (GetActiveViewOrCreate, GetAnimationScene, GetColorTransferFunction, Plane,
                             Render, SaveScreenshot, Show, Text, WarpByVector, Xdmf3ReaderS)

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else {here!r}


#: the run's shot and fidelity, for the title (fepen view passes its own with --shot)
SHOT = {shot!r}
#: a field's unit from the end of its name (fepen's names carry their units)
UNITS = {units!r}


def title(field, t, shot=SHOT):
    """The picture's title: the field and its unit, the frame's time (microseconds), the shot."""
    unit = next((u for end, u in UNITS if field.endswith(end)), "dimensionless")
    text = f"{field} ({unit}) at t = {t * 1e6:.1f} \u00b5s"
    return f"{text} \u2014 {shot}" if shot else text


def main(png=None, time=None, field="von_mises_Pa", shot=SHOT):
    reader = Xdmf3ReaderS(registrationName="fields.xdmf", FileName=[os.path.join(HERE, "fields.xdmf")])
    reader.UpdatePipelineInformation()
    points, cells = list(reader.PointArrays), list(reader.CellArrays)  # the reader's, from the file's Centers
    if field not in points + cells:  # where the field lives is the file's (its Attribute's Center)
        raise SystemExit(f"view.py: --field: {field!r} is not a field of this run; its fields: "
                         + ", ".join(points + cells))
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
    shown.ColorArrayName = ["POINTS" if field in points else "CELLS", field]
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
    text = Text(registrationName="title", Text=title(field, t, shot))
    label = Show(text, view)
    label.WindowLocation = "Upper Center"
    label.FontSize = 16
    Render(view)
    if png:
        SaveScreenshot(png, view, ImageResolution=[1200, 800])
    return view


if __name__ != "view":  # run, not imported
    parser = argparse.ArgumentParser(description="this run in ParaView")
    parser.add_argument("--png", help="render one picture to this file and exit")
    given = os.environ.get  # what fepen view gives the GUI, whose --script takes no arguments
    parser.add_argument("--time", type=float, default=given("FEPEN_VIEW_TIME"),
                        help="output time (s); default the last")
    parser.add_argument("--field", default=given("FEPEN_VIEW_FIELD", "von_mises_Pa"), help="the field to colour by")
    parser.add_argument("--shot", default=given("FEPEN_VIEW_SHOT", SHOT), help="the run's name in the title")
    args, _ = parser.parse_known_args()
    main(args.png, args.time, args.field, args.shot)
'''


def write_view_script(out: Path) -> Path:
    """Write ``view.py`` into the results directory ``out`` (rank 0's business). Returns its path."""
    from fepen.atomic import replacing

    path = Path(out) / "view.py"
    with replacing(path) as tmp:
        tmp.write_text(view_script(out))
    return path


def view_script(out: Path) -> str:
    """The text of ``view.py`` for the results directory ``out`` (VIEW_SCRIPT filled in)."""
    return (VIEW_SCRIPT.replace("{here!r}", repr(str(Path(out).resolve()))).replace("{shot!r}", repr(run_name(out)))
            .replace("{units!r}", repr(UNITS)))


def show(out: Path, field: str = "von_mises_Pa", time: float | None = None, png: str | Path | None = None) -> None:
    """``fepen view``: the run in ``out`` in ParaView on its view.py (written first for a run from before
    view.py, and rewritten when an older fepen wrote it), or by pyvista (plot) where ParaView is not installed.

    Args:
        out: results directory with fields.xdmf. field: the field to colour by. time: output time (s); None:
            the last. png: render one picture there, offscreen (pvpython, render_png), instead of opening the
            GUI.

    Raises:
        InputError: ("--field") the run has no such field (field_centre), before any window or picture.
        NoDisplay: a window asked for (no ``png``) without a display (has_display).
        ViewerFailed: the ParaView GUI exited with a non-zero code or on a signal.
    """
    import shutil
    import subprocess

    out = Path(out)
    field_centre(out, field)
    if not png and not has_display():
        raise NoDisplay()
    script = out / "view.py"
    if not script.is_file() or script.read_text(errors="replace") != view_script(out):  # a run of an older fepen
        write_view_script(out)
    if png and shutil.which("pvpython"):
        render_png(script, png, [*(["--time", repr(time)] if time is not None else []), "--field", field,
                                 "--shot", run_name(out)])
    elif not png and shutil.which("paraview"):
        given = {"FEPEN_VIEW_FIELD": field, "FEPEN_VIEW_SHOT": run_name(out),
                 **({"FEPEN_VIEW_TIME": repr(time)} if time is not None else {})}
        code = subprocess.run(["paraview", f"--script={script}"], check=False, env={**os.environ, **given}).returncode
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
    for _ in range(tries):  # Python's copy of the environment: not the one MPI_Init wrote PMIX_RANK etc. into
        r = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ))
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
        The pyvista Plotter (closed when ``png`` is given), titled by view_title.

    Raises:
        InputError: ("field") the run has no such field.
    """
    centre = field_centre(out, field, "field")
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
    plotter.add_mesh(warped, scalars=field, preference="point" if centre == "POINTS" else "cell", cmap="jet",
                     show_edges=True, edge_color="#404040",
                     scalar_bar_args={"title": field, "position_x": 0.2, "width": 0.6})
    plotter.add_mesh(face, color="grey", opacity=0.35)
    plotter.add_text(view_title(out, field, float(times[k])), position="upper_edge", font_size=10)
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
