"""Arms from plain data: the ``[arms.NAME]`` tables of a cell file.

Keys common to every arm::

    type = "gantry" | "scara" | "serial" | "urdf"
    base = [x, y, z, yaw]            # pose of the base in the cell (m, rad); default origin
    capabilities = ["gripper", ...]  # what the arm can do
    tools = ["screwdriver", ...]     # tool mounts
    payload = 3.0                    # kg
    home = [...]                     # joint vector it rests at (default per type)

``gantry`` (Cartesian, stepper axes, S1.5)::

    rails = { x = [0.0, 1.2], y = [0.0, 1.2], z = [0.0, 0.6] }   # required
    wrist = true                     # with a wrist yaw joint
    height = 0.8                     # bridge height above the base
    hand = [0.06, 0.06, 0.1]
    [arms.NAME.stepper]              # optional; S1.5 defaults
    steps_per_turn = 400
    step_length = 0.0000375          # m per step
    max_rate = 15000.0               # steps/s
    low_rate = 1000.0                # steps/s
    curve = "light"                  # of curves = { light = 2.0, loaded = 1.0 } (m/s^2)
    stop_accel = 4.0                 # steepest allowed deceleration, m/s^2

``scara``::

    link_lengths = [0.45, 0.4]
    z_range = [0.0, 0.35]
    elbow = "nearest" | "left" | "right"
    max_velocity = [3.0, 4.0, 1.0, 6.0]        # per joint
    max_acceleration = [10.0, 15.0, 5.0, 30.0]
    max_jerk = [...]                           # optional: S-curves
    joint_limits = [[lo, hi], ...]             # optional

``serial``::

    example = "6dof"                 # the built-in 6-DOF arm, or:
    dh = [[a, alpha, d, offset], ...]
    kinds = ["revolute", ...]
    joint_limits, max_velocity, max_acceleration, max_jerk, radius

``urdf`` (a robot description file, :mod:`workcell.arms.urdf`)::

    urdf = "package:example-robot-data/robots/ur_description/urdf/ur5_robot.urdf"
                                     # or a path, relative to the cell file
    tool_link = "tool0"              # the link whose frame is the flange
    joint_limits = [[lo, hi], ...]   # optional: narrower than the URDF's
    velocity_scale = 0.5             # optional: fraction of the URDF's velocity limits
    max_acceleration = [...]         # optional (default: 5/s times the velocity limits)

Every error is a :class:`~multiarm.errors.ValidationError` whose message
starts with ``where`` and the field (``cell.toml: arms.left.rails.x:
expected 2 numbers, got 'abc'``); an unknown key is an error naming it.

Examples
--------
>>> arm = arm_from_dict("a", {"type": "scara", "link_lengths": [0.4, 0.3]}, "cell.toml: arms.a")
>>> arm.kind, arm.dof
('scara', 4)
>>> arm_from_dict("b", {"type": "scara", "lenghts": 1}, "cell.toml: arms.b")
Traceback (most recent call last):
...
multiarm.errors.ValidationError: cell.toml: arms.b: unknown field 'lenghts' (known: ...)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from multiarm.errors import ValidationError
from workcell.arms._common import DriveArm, pose_xyz_yaw
from workcell.arms.gantry import CartesianGantry
from workcell.arms.profiles import StepperDrive
from workcell.arms.scara import Scara
from workcell.arms.serial import SerialArm
from workcell.arms.urdf import UrdfArm

__all__ = ["ARM_TYPES", "arm_from_dict"]

ARM_TYPES = ("gantry", "scara", "serial", "urdf")

_COMMON = {"type", "base", "capabilities", "tools", "payload", "home"}
_KEYS = {
    "gantry": _COMMON | {"rails", "wrist", "height", "hand", "stepper", "yaw_limits"},
    "scara": _COMMON
    | {
        "link_lengths",
        "z_range",
        "arm_height",
        "elbow",
        "max_velocity",
        "max_acceleration",
        "max_jerk",
        "joint_limits",
        "radius",
    },
    "serial": _COMMON
    | {
        "example",
        "dh",
        "kinds",
        "joint_limits",
        "max_velocity",
        "max_acceleration",
        "max_jerk",
        "radius",
    },
    "urdf": _COMMON | {"urdf", "tool_link", "joint_limits", "velocity_scale", "max_acceleration"},
}
_STEPPER = {
    "steps_per_turn",
    "step_length",
    "max_rate",
    "low_rate",
    "curves",
    "curve",
    "stop_accel",
    "short_steps",
    "homing_rate",
    "switch_hysteresis",
}


class _Fields:
    def __init__(self, data: Mapping[str, Any], where: str) -> None:
        self.data = data
        self.where = where

    def fail(self, key: str, msg: str) -> ValidationError:
        return ValidationError(f"{self.where}.{key}: {msg}")

    def number(
        self, key: str, default: float | None = None, positive: bool = False
    ) -> float | None:
        if key not in self.data:
            return default
        v = self.data[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(key, f"expected a number, got {v!r}")
        if positive and v <= 0:
            raise self.fail(key, f"must be > 0, got {v!r}")
        return float(v)

    def numbers(self, key: str, n: int | None = None, positive: bool = False) -> list[float] | None:
        if key not in self.data:
            return None
        v = self.data[key]
        ok = isinstance(v, list) and all(
            isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x) for x in v
        )
        if not ok or (n is not None and len(v) != n):
            count = f"{n} " if n is not None else ""
            raise self.fail(key, f"expected {count}numbers, got {v!r}")
        if positive and any(x <= 0 for x in v):
            raise self.fail(key, f"every value must be > 0, got {v!r}")
        return [float(x) for x in v]

    def pairs(self, key: str, n: int | None = None) -> list[list[float]] | None:
        if key not in self.data:
            return None
        v = self.data[key]
        ok = isinstance(v, list) and all(
            isinstance(p, list)
            and len(p) == 2
            and all(isinstance(x, int | float) and not isinstance(x, bool) for x in p)
            and math.isfinite(p[0])
            and math.isfinite(p[1])
            and p[0] < p[1]
            for p in v
        )
        if not ok or (n is not None and len(v) != n):
            raise self.fail(key, f"expected {n or ''} [low, high] pairs with low < high, got {v!r}")
        return [[float(a), float(b)] for a, b in v]

    def names(self, key: str) -> list[str]:
        v = self.data.get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            raise self.fail(key, f"expected a list of names, got {v!r}")
        return list(v)

    def text(self, key: str, choices: tuple[str, ...], default: str) -> str:
        v = self.data.get(key, default)
        if v not in choices:
            raise self.fail(key, f"expected one of {', '.join(choices)}, got {v!r}")
        return str(v)


def _check_keys(data: Mapping[str, Any], allowed: set[str], where: str) -> None:
    unknown = sorted(set(data) - allowed)
    if unknown:
        raise ValidationError(
            f"{where}: unknown field {unknown[0]!r} (known: {', '.join(sorted(allowed))})"
        )


def _stepper(data: Any, where: str) -> StepperDrive:
    if not isinstance(data, Mapping):
        raise ValidationError(f"{where}: expected a table, got {data!r}")
    _check_keys(data, _STEPPER, where)
    f = _Fields(data, where)
    kw: dict[str, Any] = {}
    for key in ("step_length", "max_rate", "low_rate", "stop_accel", "homing_rate"):
        v = f.number(key, positive=True)
        if v is not None:
            kw[key] = v
    for key in ("steps_per_turn", "short_steps", "switch_hysteresis"):
        if key in data:
            v = data[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise f.fail(key, f"expected a non-negative integer, got {v!r}")
            kw[key] = v
    if "curves" in data:
        c = data["curves"]
        if not isinstance(c, Mapping) or not c:
            raise f.fail("curves", f"expected a table of name = acceleration, got {c!r}")
        kw["curves"] = {
            str(k): _Fields(c, f"{where}.curves").number(str(k), positive=True) for k in c
        }
    if "curve" in data:
        if not isinstance(data["curve"], str):
            raise f.fail("curve", f"expected a curve name, got {data['curve']!r}")
        kw["curve"] = data["curve"]
    try:
        return StepperDrive(**kw)
    except ValidationError as exc:
        raise ValidationError(f"{where}: {exc}") from None


def _urdf_arm(
    name: str, data: Mapping[str, Any], f: _Fields, common: dict[str, Any], base_dir: Path | None
) -> UrdfArm:
    for key in ("urdf", "tool_link"):
        v = data.get(key)
        if not isinstance(v, str) or not v:
            raise f.fail(key, f"expected a non-empty string, got {v!r}")
    kw: dict[str, Any] = {}
    if (jl := f.pairs("joint_limits")) is not None:
        kw["joint_limits"] = jl
    if (vs := f.number("velocity_scale", positive=True)) is not None:
        if vs > 1:
            raise f.fail("velocity_scale", f"must be in (0, 1], got {vs!r}")
        kw["velocity_scale"] = vs
    if (acc := f.numbers("max_acceleration", positive=True)) is not None:
        kw["max_acceleration"] = acc
    try:
        return UrdfArm(
            name,
            data["urdf"],
            tool_link=data["tool_link"],
            base_dir=base_dir,
            **kw,
            **common,
        )
    except ValidationError as exc:
        # name the field: a file problem is the urdf's, a count the field's
        msg = str(exc)
        if "for tool_link" in msg:
            raise f.fail("tool_link", msg) from None
        for key in ("joint_limits", "max_acceleration", "home"):
            if key in msg:
                raise f.fail(key, msg) from None
        raise f.fail("urdf", msg) from None


def arm_from_dict(
    name: str, data: Mapping[str, Any], where: str, *, base_dir: Path | None = None
) -> DriveArm:
    """Build an arm from a cell file's ``[arms.NAME]`` table (module docstring).

    Parameters
    ----------
    name : str
        The arm's name.
    data : mapping
        The table's content.
    where : str
        Prefix of every error message (the file and the table's path).
    base_dir : Path, optional
        Directory a relative ``urdf`` path is relative to (the cell file's).

    Returns
    -------
    CartesianGantry, Scara, SerialArm or UrdfArm

    Raises
    ------
    ValidationError
        Naming the field.
    """
    if not isinstance(data, Mapping):
        raise ValidationError(f"{where}: expected a table, got {data!r}")
    kind = data.get("type")
    if kind not in ARM_TYPES:
        raise ValidationError(f"{where}.type: expected one of {', '.join(ARM_TYPES)}, got {kind!r}")
    _check_keys(data, _KEYS[kind], where)
    f = _Fields(data, where)
    base_v = f.numbers("base", 4)
    base = pose_xyz_yaw(base_v, f"{where}.base") if base_v is not None else np.eye(4)
    common: dict[str, Any] = {
        "base": base,
        "capabilities": f.names("capabilities") or ["gripper"],
        "tools": f.names("tools"),
        "payload": f.number("payload", 2.0, positive=True),
    }
    home = f.numbers("home")
    if home is not None:
        common["home"] = np.array(home)
    try:
        if kind == "gantry":
            rails_d = data.get("rails")
            if not isinstance(rails_d, Mapping):
                raise f.fail(
                    "rails",
                    f"expected a table {{ x = [lo, hi], y = ..., z = ... }}, got {rails_d!r}",
                )
            _check_keys(rails_d, {"x", "y", "z"}, f"{where}.rails")
            rf = _Fields(rails_d, f"{where}.rails")
            rails = {}
            for axis in ("x", "y", "z"):
                v = rf.numbers(axis, 2)
                if v is None:
                    raise rf.fail(axis, "missing rail [low, high]")
                if not v[0] < v[1]:
                    raise rf.fail(axis, f"needs low < high, got {v}")
                rails[axis] = (v[0], v[1])
            wrist = data.get("wrist", True)
            if not isinstance(wrist, bool):
                raise f.fail("wrist", f"expected true or false, got {wrist!r}")
            kw: dict[str, Any] = {"rails": rails, "wrist": wrist}
            if "stepper" in data:
                kw["stepper"] = _stepper(data["stepper"], f"{where}.stepper")
            if (h := f.number("height", positive=True)) is not None:
                kw["height"] = h
            if (hand := f.numbers("hand", 3, positive=True)) is not None:
                kw["hand"] = tuple(hand)
            if (yl := f.numbers("yaw_limits", 2)) is not None:
                kw["yaw_limits"] = tuple(yl)
            return CartesianGantry(name, **kw, **common)
        if kind == "scara":
            kw = {}
            if (ll := f.numbers("link_lengths", 2, positive=True)) is not None:
                kw["link_lengths"] = tuple(ll)
            if (zr := f.numbers("z_range", 2)) is not None:
                kw["z_range"] = tuple(zr)
            if (ah := f.number("arm_height", positive=True)) is not None:
                kw["arm_height"] = ah
            kw["elbow"] = f.text("elbow", ("nearest", "left", "right"), "nearest")
            for key in ("max_velocity", "max_acceleration", "max_jerk"):
                if (v := f.numbers(key, 4, positive=True)) is not None:
                    kw[key] = v
            if (jl := f.pairs("joint_limits", 4)) is not None:
                kw["joint_limits"] = jl
            if (r := f.number("radius", positive=True)) is not None:
                kw["radius"] = r
            return Scara(name, **kw, **common)
        if kind == "urdf":
            return _urdf_arm(name, data, f, common, base_dir)
        kw = {}
        example = data.get("example")
        if example is not None:
            if example != "6dof":
                raise f.fail("example", f"expected '6dof', got {example!r}")
            if "dh" in data:
                raise f.fail("dh", "give either 'example' or 'dh', not both")
            for key in ("max_velocity", "max_acceleration", "max_jerk"):
                if (v := f.numbers(key, 6, positive=True)) is not None:
                    kw[key] = v
            if (jl := f.pairs("joint_limits", 6)) is not None:
                kw["joint_limits"] = jl
            return SerialArm.example_6dof(name, **kw, **common)
        dh = data.get("dh")
        if not isinstance(dh, list) or not dh:
            raise f.fail("dh", f"expected rows of [a, alpha, d, offset], got {dh!r}")
        for i, row in enumerate(dh):
            _Fields({"row": row}, f"{where}.dh[{i}]").numbers("row", 4)
        n = len(dh)
        if "kinds" in data:
            kinds = f.names("kinds")
            if len(kinds) != n or any(k not in ("revolute", "prismatic") for k in kinds):
                raise f.fail("kinds", f"expected {n} of 'revolute'/'prismatic', got {kinds!r}")
            kw["kinds"] = kinds
        for key in ("max_velocity", "max_acceleration", "max_jerk"):
            if (v := f.numbers(key, n, positive=True)) is not None:
                kw[key] = v
        if (jl := f.pairs("joint_limits", n)) is not None:
            kw["joint_limits"] = jl
        if (r := f.number("radius", positive=True)) is not None:
            kw["radius"] = r
        return SerialArm(name, dh=dh, **kw, **common)
    except ValidationError as exc:
        msg = str(exc)
        if msg.startswith(where):
            raise
        raise ValidationError(f"{where}: {msg}") from None
