"""Layered targets: layers of target materials one behind the other, with air gaps (docs/theory.md §17).

Layers that touch form a block: inside a block each layer loads only the points between its own faces (its
immersed fraction), but the free faces that the crater, the free-surface rule and the escape lengths see are
the block's front and rear faces, so that two touching layers of one material are one layer of their summed
thickness. A gap after a layer makes its rear face free and the next layer's front face a new entry, with
its own crater. Points in a gap are not loaded. Depths are measured from the first face, y = 0, into the
target (y < 0).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fepen.laws.target import SUM_COUNT, TargetLaw

#: a layered target's run without run.end_time lasts at least this many times the time to reach its last
#: face at the striking speed (the layered demo's soil stops its body at 67 ms, where 20 x gave 60 ms)
LAYERED_TIME = 30.0


@dataclass(frozen=True)
class Layer:
    """One layer of a layered target.

    Attributes:
        name: the material's name. top: depth of its front face below y = 0 (m). thickness: m (None: the
            last layer, semi-infinite). gap: air gap after it (m). block: index of its block of touching
            layers. law: its TargetLaw in its block's frame (block front face at y = 0).
    """

    name: str
    top: float
    thickness: float | None
    gap: float
    block: int
    law: TargetLaw

    @property
    def bottom(self) -> float | None:
        """Depth of the rear face below y = 0 (m), None if semi-infinite."""
        return None if self.thickness is None else self.top + self.thickness


@dataclass(frozen=True)
class Layered:
    """A layered target: ``layers`` front to back and the front depths of their blocks.

    Attributes:
        layers: the Layer list. block_tops: depth of each block's front face (m).
    """

    layers: tuple
    block_tops: tuple


    @property
    def thickness(self) -> float | None:
        """Depth of the last rear face (m); None when the last layer is semi-infinite."""
        return self.layers[-1].bottom

    @property
    def sigma_s(self) -> float:
        """The largest quasi-static stress of the layers (Pa) (sets the rigid fidelity's step)."""
        return max(layer.law.sigma_s for layer in self.layers)

    @property
    def crater(self) -> str:
        return "energy" if any(layer.law.crater == "energy" for layer in self.layers) else "none"

    def faces(self) -> list[tuple[float, float | None]]:
        """(front, rear) depth of every layer (m)."""
        return [(layer.top, layer.bottom) for layer in self.layers]

    def hard_end(self, default: float, speed: float) -> float:
        """The latest a run without run.end_time lasts (s): long enough to reach the last face.

        Args:
            default: the fidelity's longest run (s). speed: the striking speed (m/s).

        Returns:
            The default, or LAYERED_TIME times the time to reach the last front face at ``speed`` if longer.
        """
        return max(default, LAYERED_TIME * self.faces()[-1][0] / speed)

    def crossings(self) -> Crossings:
        """A record of each layer's entry and exit for one run."""
        return Crossings(self.faces())

    def point_forces(self, kernel, x, v, n, area, radius, R_meridian, sin_phi0, axis, tunnel=None, body_xi=None):
        """Each layer's law on the points near it, in its block's frame; forces (k, 3) and their sums (force
        (3), loaded points, loaded area), as fepen.laws.target.point_forces returns them.

        A layer near any point takes all of them, shifted into its block's frame: the law's immersed fraction
        is zero on the points whose patch lies wholly outside the layer's faces (no force, not counted), so
        the forces are those of the points near it, without gathering them into new arrays every call.

        Args:
            kernel: fepen.laws.target.point_forces. x, v, n, area, radius, R_meridian, sin_phi0, axis: as it
                takes them. tunnel, body_xi: unused (no tunnel through layers; the one signature of every
                target law's point_forces).

        Returns:
            (forces (k, 3), sums (5,)).
        """
        f = np.zeros_like(x)
        sums = np.zeros(SUM_COUNT)
        lo, hi = float(x[:, 1].min(initial=np.inf)), float(x[:, 1].max(initial=-np.inf))
        reach = 0.5 * float(np.sqrt(area.max(initial=0.0)))
        for layer in self.layers:
            d = self.block_tops[layer.block]
            if lo + d >= -layer.law.top + reach or (layer.law.lower is not None and hi + d <= -layer.law.lower - reach):
                continue  # no point near this layer
            xs = x.copy()
            xs[:, 1] += d  # in the block's frame
            fi, si = kernel(layer.law, xs, v, n, area, radius, R_meridian, sin_phi0, axis)
            f += fi
            sums += si
        return f, sums


def build(layers: list[dict], law_of) -> Layered:
    """A Layered target from resolved layer tables.

    Args:
        layers: [{"material": name, "thickness": m or None (the last only), "gap": m, ...}] front to back.
        law_of: a function (layer dict) -> TargetLaw of that layer's material on its own (face at y = 0,
            its thickness), as fepen.runs.setup makes it.

    Returns:
        The Layered target.
    """
    # blocks of touching layers
    tops, blocks, block_tops, block_of = [], [], [], []
    depth = 0.0
    for i, layer in enumerate(layers):
        if i == 0 or layers[i - 1]["gap"] > 0.0:
            block_tops.append(depth)
            blocks.append([])
        blocks[-1].append(i)
        block_of.append(len(blocks) - 1)
        tops.append(depth)
        if layer.get("thickness") is not None:
            depth += layer["thickness"] + layer["gap"]
    out = []
    for i, layer in enumerate(layers):
        b = block_of[i]
        last = layers[blocks[b][-1]]
        block_thk = None if last.get("thickness") is None else tops[blocks[b][-1]] + last["thickness"] - block_tops[b]
        law = law_of(layer)
        top = tops[i] - block_tops[b]
        bottom = None if layer.get("thickness") is None else top + layer["thickness"]
        law = replace(law, thickness=block_thk, top=top, bottom=bottom)
        out.append(Layer(layer["material"], tops[i], layer.get("thickness"), layer["gap"], b, law))
    return Layered(tuple(out), tuple(block_tops))


@dataclass
class Crossings:
    """Entry and exit of each layer during a run: the time and the speed of the centre of mass when the nose
    tip first reaches a layer's front face, and when every load point has passed its rear face (linear
    interpolation between two updates).

    Args:
        faces: (front, rear) depth of each layer (m), rear None when semi-infinite.
    """

    faces: list
    last: tuple | None = None

    def __post_init__(self):
        self.entry = [None] * len(self.faces)
        self.exit = [None] * len(self.faces)

    def update(self, t: float, tip_depth: float, rear_depth: float, speed: float) -> None:
        """One sample: time (s), the nose tip's depth, the shallowest load point's depth (m), the speed (m/s)."""
        if self.last is None:  # the first sample: layers already reached count from now
            for i, (front, _) in enumerate(self.faces):
                if front <= tip_depth and self.entry[i] is None:
                    self.entry[i] = (t, speed)
        else:
            t0, d0, r0, s0 = self.last
            for i, (front, rear) in enumerate(self.faces):
                if self.entry[i] is None and d0 < front <= tip_depth:
                    w = (front - d0) / (tip_depth - d0)
                    self.entry[i] = (t0 + w * (t - t0), s0 + w * (speed - s0))
                if rear is not None and self.exit[i] is None and r0 <= rear < rear_depth:
                    w = (rear - r0) / (rear_depth - r0)
                    self.exit[i] = (t0 + w * (t - t0), s0 + w * (speed - s0))
        self.last = (t, tip_depth, rear_depth, speed)

    def state(self) -> dict:
        return {"entry": self.entry, "exit": self.exit, "last": self.last}

    def restore(self, state: dict) -> None:
        self.entry = [tuple(e) if e is not None else None for e in state["entry"]]
        self.exit = [tuple(e) if e is not None else None for e in state["exit"]]
        self.last = tuple(state["last"]) if state["last"] is not None else None

    def summary(self, target: Layered, deepest: float) -> dict:
        """Per layer its material, faces and entry and exit (time, speed), and the deepest tip depth in the last
        layer entered (mm)."""
        rows, last = [], None
        for i, layer in enumerate(target.layers):
            e, x = self.entry[i], self.exit[i]
            rows.append({"material": layer.name, "top_m": layer.top, "thickness_m": layer.thickness,
                         "gap_m": layer.gap,
                         "entry_time_s": e[0] if e else None, "entry_speed_m_s": e[1] if e else None,
                         "exit_time_s": x[0] if x else None, "exit_speed_m_s": x[1] if x else None})
            if e is not None:
                last = layer
        depth_last = None if last is None else 1e3 * max(deepest - last.top, 0.0)
        return {"layers": rows, "depth_in_last_layer_mm": depth_last}
