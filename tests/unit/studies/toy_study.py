"""A new study is one file (issue 44): the depth of the rigid C3 shot at a few striking speeds, with the slope
of ln(depth) against ln(speed), a report and a figure. fepen.study("toy-ladder", speeds=[...]) runs it."""

import math

from fepen import scene
from fepen.studies.study import STUDIES, Round, Study, register

STUDIES["toy-ladder"] = (__name__, "ToyLadder")


@register
class ToyLadder(Study):
    name = "toy-ladder"
    help = "the rigid C3 shot's depth at a few speeds"
    names = ("shots.jsonl", "toy_ladder.json", "toy_ladder.md", "toy_ladder.png")

    def plan(self, speeds=(400.0, 600.0, 800.0)):
        return [float(v) for v in speeds]

    def digest(self, speeds):
        return repr(speeds)

    def rounds(self, speeds):
        yield Round([scene.load(None, ["effects.fidelity=rigid", f"impact.velocity={v}"]) for v in speeds])

    def result(self, speeds, records, info):
        depth = [records[0][i]["summary"]["depth_mm"] for i in range(len(speeds))]
        x, y = [math.log(v) for v in speeds], [math.log(d) for d in depth]
        slope = (y[-1] - y[0]) / (x[-1] - x[0])
        return {"speeds_m_s": speeds, "depth_mm": depth, "slope": slope}

    def report(self, result):
        rows = [f"| {v:g} | {d:.1f} |" for v, d in zip(result["speeds_m_s"], result["depth_mm"])]
        return "\n".join(["| speed (m/s) | depth (mm) |", "|---|---|", *rows, ""])

    def figure(self, result, fig):
        ax = fig.subplots()
        ax.loglog(result["speeds_m_s"], result["depth_mm"], "o-")
        return True

    def lines(self, result):
        return [f"ln depth / ln speed: {result['slope']:.3f}"]
