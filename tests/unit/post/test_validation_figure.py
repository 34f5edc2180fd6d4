"""validation.png legible (issue 61): the shots' names beside their points never overlap one another, the
legends or the axes' edges, each name stays near its point (a leader line where it had to move), at the size
and resolution `fepen validate` draws it (its declared Picture), on the rigid validation's own numbers
(docs/validation.md), whose clustered points made the names collide."""

from types import SimpleNamespace

import numpy as np
import pytest

#: the rigid validation's results (docs/validation.md's table): Hx, Hy, Tx, Ty (mm)
RIGID = {"C1": (35.5, 291.9, 17.7, 149.0), "C2": (2.4, 335.6, 1.4, 191.6), "C3": (68.3, 352.4, 40.8, 211.0),
         "C4": (88.0, 482.0, 61.9, 340.4), "C5": (109.0, 620.0, 84.1, 478.2), "C6": (144.6, 339.7, 87.1, 207.6),
         "C7": (219.0, 581.7, 168.3, 447.0), "C8": (7.2, 709.6, 5.8, 565.6)}


def rows_and_histories(out, results=RIGID):
    """validate's rows for the Table 1 shots, and each shot's history.csv (a straight path to its nose)."""
    from fepen.data import SHOTS

    rows = []
    for name, (hx, hy, tx, ty) in results.items():
        s = SHOTS[name]
        rows.append({"shot": name, "Hx_mm": hx, "Hy_mm": hy, "Tx_mm": tx, "Ty_mm": ty, "Hx_exp_mm": s.Hx_mm,
                     "Hy_exp_mm": s.Hy_mm, "Tx_exp_mm": s.Tx_mm, "Ty_exp_mm": s.Ty_mm})
        (out / name).mkdir()
        f = np.linspace(0.0, 1.0, 20)
        np.savetxt(out / name / "history.csv", np.column_stack([f * 1e-3, f * hx, f * hy]), delimiter=",",
                   header="t_s,nose_x_mm,nose_y_mm", comments="", fmt="%.9g")
    return rows


def draw_validation(out, rows):
    """validation.png's Figure as `fepen validate` draws it: the study's declared Picture (size, dpi)."""
    from fepen.post.figures import new_figure
    from fepen.studies.validate import Validate

    study = Validate.__new__(Validate)  # pictures() needs neither the study's state nor the plan for this one
    picture = next(p for p in study.pictures(None, {"rows": rows}, SimpleNamespace(out=out))
                   if p.file == "validation.png")
    fig = new_figure(picture.size)
    fig.set_dpi(picture.dpi or 110)
    picture.draw(fig)
    fig.canvas.draw()
    return fig


def shot_labels(ax) -> list:
    """The texts of an axes that name a shot (C1 ... C8)."""
    return [t for t in ax.texts if t.get_text() in RIGID and t.get_visible()]


def overlaps(a, b, pad=0.0) -> bool:
    return a.x0 < b.x1 + pad and b.x0 < a.x1 + pad and a.y0 < b.y1 + pad and b.y0 < a.y1 + pad


@pytest.mark.parametrize("results", ["rigid", "exact"])
def test_the_shot_names_do_not_collide(tmp_path, results):
    """Every shot's name on the two scatter panels: a box of its own (no overlap with another name or the
    legend, no marker's centre under it), inside its axes, within 70 points of its point."""
    from fepen.data import SHOTS

    given = RIGID if results == "rigid" else {k: (s.Hx_mm, s.Hy_mm, s.Tx_mm, s.Ty_mm) for k, s in SHOTS.items()}
    rows = rows_and_histories(tmp_path, given)
    fig = draw_validation(tmp_path, rows)
    renderer = fig.canvas.get_renderer()
    scatter = [ax for ax in fig.axes if len(shot_labels(ax)) == 2 * len(rows)]
    assert len(scatter) == 2, "each of the two scatter panels names every shot's nose and tail"
    for ax in scatter:
        boxes = [t.get_window_extent(renderer) for t in shot_labels(ax)]
        for i in range(len(boxes)):
            for j in range(i):
                assert not overlaps(boxes[i], boxes[j]), (ax.get_title(), shot_labels(ax)[i].get_text(),
                                                           shot_labels(ax)[j].get_text())
        legend = ax.get_legend()
        frame = ax.get_window_extent(renderer)
        markers = np.vstack([ax.transData.transform(line.get_xydata()) for line in ax.lines
                             if line.get_marker() not in (None, "None", "", " ")])
        for t, box in zip(shot_labels(ax), boxes):
            covered = (markers[:, 0] > box.x0) & (markers[:, 0] < box.x1) & (markers[:, 1] > box.y0) \
                & (markers[:, 1] < box.y1)
            assert not covered.any(), (t.get_text(), "covers a marker")
            if legend is not None:
                assert not overlaps(box, legend.get_window_extent(renderer)), t.get_text()
            assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
            point = ax.transData.transform(t.xy)
            gap = max(box.x0 - point[0], point[0] - box.x1, box.y0 - point[1], point[1] - box.y1, 0.0)
            assert gap <= 70 * fig.dpi / 72, (t.get_text(), gap)
