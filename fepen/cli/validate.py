"""``fepen validate [SCENE.toml] [--out DIR] [--set KEY=VALUE ...]``: the eight Table 1 shots
(fepen.studies.validate), one line per shot."""

from __future__ import annotations

from fepen.cli.common import say, scene_arguments

HELP = "the Table 1 sweep: validation.csv, validation.md, figures"


def add_arguments(parser) -> None:
    scene_arguments(parser, "results/validation")


def run(args) -> int:
    """The eight Table 1 shots."""
    from fepen.studies import validate

    rows = validate.validate(args.scene, args.sets, args.out)
    say(*(f"{r['shot']}: Hx {r['Hx_mm']:.1f}/{r['Hx_exp_mm']:g} Hy {r['Hy_mm']:.1f}/{r['Hy_exp_mm']:g} "
          f"Tx {r['Tx_mm']:.1f}/{r['Tx_exp_mm']:g} Ty {r['Ty_mm']:.1f}/{r['Ty_exp_mm']:g} mm  nose error "
          f"{100 * r['nose_error']:.1f} %  tail error {100 * r['tail_error']:.1f} %  {r['outcome']}" for r in rows),
        f"written: {args.out}/validation.csv, validation.md, validation.png")
    return 0
