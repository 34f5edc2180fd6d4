"""``fepen study uncertainty --workers W``: accepted, W < 1 refused in one line, and the words the relaunch
gives mpirun's ranks are the study's own options again (the relaunch itself: tests/system/
test_uncertainty_workers.py)."""

from fepen import cli
from fepen.studies import processes

ARGV = ["study", "uncertainty", "scene.toml", "--set", "impact.velocity=600", "--scatter", "s.toml", "--samples",
        "12", "--seed", "7", "--no-model-scatter", "--striking", "--axis-beyond", "5"]


def parse(argv):
    return cli._parser().parse_args(argv)


def test_the_relaunched_words_give_the_same_options():
    from fepen.studies import study

    cls = study.get("uncertainty")
    args = parse([*ARGV, "--workers", "2"])
    assert args.workers == 2
    again = parse(["study", "uncertainty", *cls.argv(args)])
    assert cls.options(again) == cls.options(args)
    plain = parse(["study", "uncertainty"])
    assert plain.workers == 1 and cls.argv(plain) == []


def test_workers_below_one_is_bad_input(monkeypatch, capsys, bad_input_line, tmp_path):
    monkeypatch.chdir(tmp_path)
    code = cli.main(["study", "uncertainty", "--samples", "4", "--workers", "0", "--out", "o"])
    bad_input_line(code, capsys.readouterr().err, "--workers", r"must be at least 1, got 0")
    assert not (tmp_path / "o").exists()


def test_workers_relaunch_the_study_with_its_options(monkeypatch, tmp_path):
    """Started on one rank with W > 1: the same study, its options, --out and --ranks-per-shot, under W ranks."""
    got = {}
    monkeypatch.setattr(processes, "launcher", lambda *a: "mpirun")
    monkeypatch.setattr(processes, "relaunch", lambda argv, workers: got.update(argv=argv, workers=workers) or 0)
    monkeypatch.chdir(tmp_path)
    assert cli.main(["study", "uncertainty", "--samples", "4", "--seed", "2", "--workers", "2", "--out", "o"]) == 0
    assert got["workers"] == 2
    assert got["argv"] == ["study", "uncertainty", "--samples=4", "--seed=2", "--out", "o", "--ranks-per-shot", "1"]
    assert not (tmp_path / "o").exists()  # nothing ran here
