"""The one reader of results directories (fepen.io.results.RunFiles): what fepen.load, the figures, ParaView's
help and the tools read, from a directory written by hand."""

import json

import numpy as np

from fepen.io import results


def _run(d, scene_toml=None, summary=None):
    d.mkdir()
    (d / "history.csv").write_text("t_s,nose_y_mm\n0,0.000000e+00\n1e-05,-5.840000e+00\n")
    if summary is not None:
        (d / "summary.json").write_text(json.dumps(summary))
    if scene_toml is not None:
        (d / "scene.toml").write_text(scene_toml)
    return d


def test_a_finished_run_reads_back(tmp_path):
    d = _run(tmp_path / "C3", "[impact]\nvelocity = 584.3\n# [effects]\n# fidelity = \"rigid\"\n",
             {"outcome": "embedded", "scene": {"impact": {"velocity": 1.0}}})
    f = results.read(d)
    assert f.finished and f.summary()["outcome"] == "embedded"
    h = f.history()
    assert h["nose_y_mm"][-1] == -5.84 and len(h) == 2
    cols, rows = f.history_text()
    assert cols == ["t_s", "nose_y_mm"] and rows[1] == ["1e-05", "-5.840000e+00"]  # as written, to the character
    # scene.toml wins over summary.json's scene; its commented resolved keys are read too
    assert f.scene_keys() == {"impact.velocity": 584.3, "effects.fidelity": "rigid"}
    assert f.given_scene() == {"impact": {"velocity": 584.3}}
    assert f.fields() is None and f.figures() == {}


def test_an_unfinished_or_foreign_directory_reads_as_empty(tmp_path):
    d = _run(tmp_path / "killed")
    f = results.read(d)
    assert not f.finished and f.summary() is None and f.scene_keys() == {} and f.given_scene() == {}
    (d / "summary.json").write_text("{not json")
    assert f.summary() is None  # a torn file is no summary
    # without scene.toml the summary's scene is flattened
    (d / "summary.json").write_text(json.dumps({"scene": {"impact": {"velocity": 600.0, "obliquity_deg": 10.0}}}))
    assert f.scene_keys() == {"impact.velocity": 600.0, "impact.obliquity_deg": 10.0}


def test_finished_runs_of_a_folder(tmp_path):
    study = tmp_path / "study"
    study.mkdir()
    for name, done in (("b", True), ("a", True), ("c", False)):
        _run(study / name, summary={"outcome": "embedded"} if done else None)
    assert [p.name for p in results.finished_runs(study)] == ["a", "b"]
    assert results.finished_runs(study / "a") == [study / "a"]
    assert np.isfinite(results.read(study / "a").history()["t_s"]).all()


def test_history_text_formats_each_row_once_and_gives_the_whole_text(tmp_path):
    """history.csv is replaced whole at every output: a run's history_rows() formats only the rows added since
    its last write (fepen.io.table.Rows), and its text is, to the character, that of every row formatted afresh;
    a list whose earlier rows changed (a row inserted at its head, as the batched rigid path does) is formatted
    again."""
    import csv
    import io

    def afresh(rows):
        buf = io.StringIO()
        w = csv.writer(buf)
        for r in rows:
            w.writerow([f"{v:.9g}" for v in r])
        return buf.getvalue()

    rng = np.random.default_rng(3)
    text, rows = results.history_rows(), []
    for n in (1, 5, 0, 40, 3):
        rows.extend(list(rng.normal(size=6) * 10.0 ** rng.integers(-9, 9)) for _ in range(n))
        assert text.of(rows) == afresh(rows)
    assert len(text.chunks) == 4  # one chunk per write that added rows: none were formatted twice
    rows.insert(0, [0.5] * 6)
    assert text.of(rows) == afresh(rows) and len(text.chunks) == 1
    restored = [list(r) for r in rows[:10]]  # a resumed run's rows: new objects, fewer
    assert text.of(restored) == afresh(restored)
    results.write_history(rows, tmp_path, text=text)
    assert (tmp_path / "history.csv").read_text().splitlines()[1:] == afresh(rows).splitlines()
