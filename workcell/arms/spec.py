"""Arms from plain data: the ``[arms.NAME]`` tables of a cell file.

:data:`ARM_KEYS` lists every key of every arm kind with its unit, default,
allowed range and meaning; :func:`arm_keys_markdown` prints it as the
reference tables of ``docs/workcell.md`` (a test keeps the two equal), and
:func:`arm_from_dict` checks each number against its range (lengths and
coordinates within 100 m, speeds, accelerations, rates and masses within
1e-6 .. 1e6 of their units). An example::

    [arms.left]
    type = "gantry"
    base = [0.0, 0.0, 0.0, 0.0]          # x, y, z (m), yaw (rad)
    rails = { x = [0.0, 1.2], y = [0.0, 1.2], z = [0.0, 0.6] }
    capabilities = ["gripper"]
    [arms.left.stepper]
    curve = "loaded"

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
from dataclasses import dataclass
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

__all__ = ["ARM_KEYS", "ARM_TYPES", "ArmKey", "arm_from_dict", "arm_keys_markdown"]

ARM_TYPES = ("gantry", "scara", "serial", "urdf")

MAX_LENGTH = 100.0
"""Largest length or coordinate in a cell, metres (and largest angle, radians)."""
SMALL, LARGE = 1e-6, 1e6
"""Bounds of speeds, accelerations, jerks, rates, times and masses, in their units."""


@dataclass(frozen=True, slots=True)
class ArmKey:
    """One key of an ``[arms.NAME]`` table: the docs' reference row and the check's range.

    Parameters
    ----------
    name : str
        The key.
    unit : str
        Unit of its numbers (``""`` for none).
    default : str
        Its default, as written in the reference (``"required"`` when none).
    meaning : str
        One line for the reference.
    lo, hi : float or None
        Every number of the value must lie in ``[lo, hi]`` (checked by
        :func:`arm_from_dict`); ``None`` for a value that is not numbers.
    allowed : str
        The allowed values when they are not a numeric range.
    """

    name: str
    unit: str
    default: str
    meaning: str
    lo: float | None = None
    hi: float | None = None
    allowed: str = ""

    def allowed_text(self) -> str:
        """The allowed range or values, as the reference prints them."""
        if self.lo is None or self.hi is None:
            return self.allowed
        return f"{_num(self.lo)} .. {_num(self.hi)}" + (f"; {self.allowed}" if self.allowed else "")


def _num(v: float) -> str:
    if v == int(v) and abs(v) < 1e5:
        return str(int(v))
    return f"{v:g}"


_L, _P = MAX_LENGTH, (SMALL, LARGE)
ARM_KEYS: dict[str, tuple[ArmKey, ...]] = {
    "common": (
        ArmKey(
            "type", "", "required", "the arm kind", allowed='"gantry", "scara", "serial", "urdf"'
        ),
        ArmKey(
            "base",
            "m, m, m, rad",
            "[0, 0, 0, 0]",
            "[x, y, z, yaw] of the arm's base frame in the cell",
            -_L,
            _L,
        ),
        ArmKey(
            "capabilities",
            "",
            '["gripper"]',
            "what the arm can do (a task needs all of its own and its steps' capabilities); "
            "[] is an arm with none, which can do only tasks needing none",
            allowed="a list of names",
        ),
        ArmKey(
            "tools",
            "",
            "[]",
            "tool mounts: the tools of tasks it may do",
            allowed="a list of names",
        ),
        ArmKey("payload", "kg", "2.0", "largest part mass it carries", *_P),
        ArmKey(
            "home",
            "joint units",
            "per kind, below",
            "joint vector it rests at; its start by default",
            -_L,
            _L,
            "within the joint limits",
        ),
        ArmKey(
            "start",
            "joint units",
            "home",
            "initial joint vector of the run; between tasks the arm parks here "
            '(compile.park = "home")',
            -_L,
            _L,
            "within the joint limits",
        ),
    ),
    "gantry": (
        ArmKey(
            "rails",
            "m",
            "required",
            "{ x = [lo, hi], y = [lo, hi], z = [lo, hi] }: travel of each axis, "
            "in the base frame; z is the height of the tool point",
            -_L,
            _L,
            "lo < hi",
        ),
        ArmKey("wrist", "", "true", "with a yaw joint turning the hand", allowed="true, false"),
        ArmKey("yaw_limits", "rad", "[-pi, pi]", "limits of the wrist yaw", -_L, _L, "lo < hi"),
        ArmKey("height", "m", "z hi + 0.15", "height of the bridge beam above the base", SMALL, _L),
        ArmKey("hand", "m", "[0.06, 0.06, 0.1]", "size of the hand box [dx, dy, dz]", SMALL, _L),
        ArmKey(
            "stepper",
            "",
            "S1.5 defaults",
            "the x, y, z stepper drives: an [arms.NAME.stepper] table, below",
            allowed="a table",
        ),
    ),
    "gantry.stepper": (
        ArmKey("steps_per_turn", "steps", "400", "steps per motor turn (half-step mode)", 1, LARGE),
        ArmKey(
            "step_length",
            "m",
            "3.75e-05",
            "arm travel per step",
            1e-9,
            0.1,
            "top speed max_rate x step_length in 1e-06 .. 1e+06 m/s",
        ),
        ArmKey("max_rate", "steps/s", "15000", "top step rate (562.5 mm/s by default)", 1, LARGE),
        ArmKey(
            "low_rate",
            "steps/s",
            "1000",
            "start/stop rate, no ramp; short moves run at it",
            1,
            LARGE,
            "<= max_rate",
        ),
        ArmKey(
            "curves",
            "m/s^2",
            "{ light = 2.0, loaded = 1.0 }",
            "named accelerations of travel",
            *_P,
        ),
        ArmKey("curve", "", '"light"', "the curve in use", allowed="a name of curves"),
        ArmKey(
            "stop_accel",
            "m/s^2",
            "4.0",
            "steepest allowed deceleration (emergency stops)",
            *_P,
            ">= every curve",
        ),
        ArmKey(
            "short_steps",
            "steps",
            "32",
            "moves of at most this many steps run at low_rate",
            0,
            LARGE,
        ),
        ArmKey(
            "homing_rate", "steps/s", "4000", "rate while seeking the end-of-rail switch", 1, LARGE
        ),
        ArmKey(
            "switch_hysteresis", "steps", "40", "steps forward until the switch releases", 0, LARGE
        ),
    ),
    "scara": (
        ArmKey("link_lengths", "m", "[0.45, 0.4]", "lengths of link 1 and link 2", SMALL, _L),
        ArmKey(
            "z_range",
            "m",
            "[0.0, 0.35]",
            "[lo, hi] height of the tool point (the quill)",
            -_L,
            _L,
            "lo < hi",
        ),
        ArmKey("arm_height", "m", "z hi + 0.12", "height of the links above the base", SMALL, _L),
        ArmKey(
            "elbow",
            "",
            '"nearest"',
            "IK branch: the one nearest the previous joints, or always left or right",
            allowed='"nearest", "left", "right"',
        ),
        ArmKey(
            "max_velocity",
            "rad/s, rad/s, m/s, rad/s",
            "[3.0, 4.0, 1.0, 6.0]",
            "top speed of each joint (j1, j2, z, wrist)",
            *_P,
        ),
        ArmKey(
            "max_acceleration",
            "rad/s^2, rad/s^2, m/s^2, rad/s^2",
            "[10.0, 15.0, 5.0, 30.0]",
            "acceleration limit of each joint",
            *_P,
        ),
        ArmKey(
            "max_jerk",
            "rad/s^3, rad/s^3, m/s^3, rad/s^3",
            "none (trapezoids)",
            "jerk limit of each joint: S-curves",
            *_P,
        ),
        ArmKey(
            "joint_limits",
            "rad, rad, m, rad",
            "[±170°, ±150°, z_range, ±360°]",
            "4 [lo, hi] pairs",
            -_L,
            _L,
            "lo < hi",
        ),
        ArmKey("radius", "m", "0.04", "radius of the link capsules", SMALL, _L),
    ),
    "serial": (
        ArmKey(
            "example",
            "",
            "none",
            "the built-in 6-DOF arm (about 0.9 m reach) instead of dh",
            allowed='"6dof"',
        ),
        ArmKey(
            "dh",
            "m, rad, m, rad",
            "required without example",
            "standard Denavit-Hartenberg rows [a, alpha, d, offset], one a joint",
            -_L,
            _L,
        ),
        ArmKey(
            "kinds",
            "",
            "all revolute",
            "joint kinds, one a row of dh",
            allowed='"revolute", "prismatic"',
        ),
        ArmKey(
            "joint_limits",
            "rad or m",
            "[-pi, pi] each",
            "one [lo, hi] pair a joint",
            -_L,
            _L,
            "lo < hi",
        ),
        ArmKey(
            "max_velocity",
            "rad/s or m/s",
            "2.0 each (6dof: [2.5, 2.5, 3, 5, 5, 7])",
            "top speed of each joint",
            *_P,
        ),
        ArmKey(
            "max_acceleration",
            "rad/s^2 or m/s^2",
            "8.0 each (6dof: [8, 8, 10, 20, 20, 30])",
            "acceleration limit of each joint",
            *_P,
        ),
        ArmKey(
            "max_jerk",
            "rad/s^3 or m/s^3",
            "none (trapezoids)",
            "jerk limit of each joint: S-curves",
            *_P,
        ),
        ArmKey("radius", "m", "0.05", "radius of the link capsules", SMALL, _L),
    ),
    "urdf": (
        ArmKey(
            "urdf",
            "",
            "required",
            "the robot description: a path (relative to the cell file) or "
            '"package:example-robot-data/robots/..." (workcell.arms.urdf)',
            allowed="a URDF file",
        ),
        ArmKey(
            "tool_link", "", "required", "the link whose frame is the flange", allowed="a link name"
        ),
        ArmKey(
            "joint_limits",
            "rad or m",
            "the URDF's",
            "one [lo, hi] pair a joint, narrower than the URDF's",
            -_L,
            _L,
            "lo < hi",
        ),
        ArmKey(
            "velocity_scale", "", "1.0", "fraction of the URDF's velocity limits used", SMALL, 1.0
        ),
        ArmKey(
            "max_acceleration",
            "rad/s^2 or m/s^2",
            "5/s x the velocity limits",
            "acceleration limit of each joint",
            *_P,
        ),
    ),
}
"""Every key of an ``[arms.NAME]`` table, per section: ``"common"`` (every
kind), ``"gantry"``, ``"gantry.stepper"``, ``"scara"``, ``"serial"``. The
reference tables of ``docs/workcell.md`` are :func:`arm_keys_markdown`."""

HOMES: dict[str, str] = {
    "gantry": "[x lo, middle of y, z hi, 0]: at the low-x end of its x rail, in the middle of "
    "the y rail, raised to the top of z, tool down",
    "scara": "[0, pi/2, z hi, 0]: link 1 along the base's x axis, the elbow bent a right angle "
    "to the left, so the hand stands at (l1, l2) in the base frame (0.45 m ahead, 0.4 m to the "
    "left with the default links), raised: it reaches across the table, so a SCARA next to other "
    "arms needs a start that points away from them",
    "urdf": "all joints 0, or the middle of a joint's limits when 0 is outside them (the URDF's "
    "zero pose)",
    "serial": "all joints 0 (6dof: [0, 0.3, 0.9, 0, 1.2, 0], the hand in front of the base, "
    "pointing down)",
}
"""Where each kind's default ``home`` (and so its default ``start``) points."""

_KEYS = {
    kind: {k.name for k in ARM_KEYS["common"] if k.name != "start"}
    | {k.name for k in ARM_KEYS[kind]}
    for kind in ARM_TYPES
}
_STEPPER = {k.name for k in ARM_KEYS["gantry.stepper"]}
_META = {section: {k.name: k for k in keys} for section, keys in ARM_KEYS.items()}


def arm_keys_markdown() -> str:
    """The reference tables of the arm keys (``docs/workcell.md``), from :data:`ARM_KEYS`."""
    titles = {
        "common": "Every arm",
        "gantry": '`type = "gantry"`',
        "gantry.stepper": "`[arms.NAME.stepper]` (gantry)",
        "scara": '`type = "scara"`',
        "serial": '`type = "serial"`',
        "urdf": '`type = "urdf"`',
    }
    out: list[str] = []
    for section, keys in ARM_KEYS.items():
        out += [f"**{titles[section]}**", ""]
        out += ["| key | unit | default | allowed | meaning |", "|---|---|---|---|---|"]
        for k in keys:
            cells = (f"`{k.name}`", k.unit, k.default, k.allowed_text(), k.meaning)
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        if section in HOMES:
            out += ["", f"Default `home`: {HOMES[section]}."]
        out.append("")
    return "\n".join(out).rstrip() + "\n"


class _Fields:
    def __init__(self, data: Mapping[str, Any], where: str, section: str = "") -> None:
        self.data = data
        self.where = where
        self.section = section

    def fail(self, key: str, msg: str) -> ValidationError:
        return ValidationError(f"{self.where}.{key}: {msg}")

    def _meta(self, key: str, bounds: ArmKey | None) -> ArmKey | None:
        if bounds is not None:
            return bounds
        return _META.get(self.section, {}).get(key) or _META["common"].get(key)

    def _in_range(self, key: str, values: list[float], bounds: ArmKey | None) -> None:
        meta = self._meta(key, bounds)
        if meta is None or meta.lo is None or meta.hi is None:
            return
        lo, hi = meta.lo, meta.hi
        bad = [v for v in values if not lo <= v <= hi]
        if bad:
            unit = f" {meta.unit}" if meta.unit else ""
            raise self.fail(
                key, f"{bad[0]:g} is out of range: every value must be in [{lo:g}, {hi:g}]{unit}"
            )

    def number(
        self,
        key: str,
        default: float | None = None,
        positive: bool = False,
        bounds: ArmKey | None = None,
    ) -> float | None:
        if key not in self.data:
            return default
        v = self.data[key]
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise self.fail(key, f"expected a number, got {v!r}")
        if positive and v <= 0:
            raise self.fail(key, f"must be > 0, got {v!r}")
        self._in_range(key, [float(v)], bounds)
        return float(v)

    def numbers(
        self, key: str, n: int | None = None, positive: bool = False, bounds: ArmKey | None = None
    ) -> list[float] | None:
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
        out = [float(x) for x in v]
        self._in_range(key, out, bounds)
        return out

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
        out = [[float(a), float(b)] for a, b in v]
        self._in_range(key, [x for p in out for x in p], None)
        return out

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
    f = _Fields(data, where, "gantry.stepper")
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
            f._in_range(key, [float(v)], None)
            kw[key] = v
    if "curves" in data:
        c = data["curves"]
        if not isinstance(c, Mapping) or not c:
            raise f.fail("curves", f"expected a table of name = acceleration, got {c!r}")
        cf = _Fields(c, f"{where}.curves")
        bounds = _META["gantry.stepper"]["curves"]
        kw["curves"] = {str(k): cf.number(str(k), positive=True, bounds=bounds) for k in c}
    if "curve" in data:
        if not isinstance(data["curve"], str):
            raise f.fail("curve", f"expected a curve name, got {data['curve']!r}")
        kw["curve"] = data["curve"]
    try:
        drive = StepperDrive(**kw)
    except ValidationError as exc:
        raise ValidationError(f"{where}: {exc}") from None
    if not SMALL <= drive.top_speed <= LARGE:
        raise ValidationError(
            f"{where}: top speed max_rate x step_length = {drive.top_speed:g} m/s is out of range: "
            f"it must be in [{SMALL:g}, {LARGE:g}] m/s"
        )
    return drive


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
    if not isinstance(name, str) or not name.strip() or "|" in name or "/" in name:
        raise ValidationError(
            f"{where}: an arm's name must be non-empty text without '|' or '/', got {name!r}"
        )
    if not isinstance(data, Mapping):
        raise ValidationError(f"{where}: expected a table, got {data!r}")
    kind = data.get("type")
    if kind not in ARM_TYPES:
        raise ValidationError(f"{where}.type: expected one of {', '.join(ARM_TYPES)}, got {kind!r}")
    _check_keys(data, _KEYS[kind], where)
    f = _Fields(data, where, kind)
    base_v = f.numbers("base", 4)
    base = pose_xyz_yaw(base_v, f"{where}.base") if base_v is not None else np.eye(4)
    common: dict[str, Any] = {
        "base": base,
        # an empty list is an arm with no capability (docs/workcell.md), not the default
        "capabilities": f.names("capabilities") if "capabilities" in data else ["gripper"],
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
                v = rf.numbers(axis, 2, bounds=_META["gantry"]["rails"])
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
                if not yl[0] < yl[1]:
                    raise f.fail("yaw_limits", f"needs low < high, got {yl}")
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
            if "kinds" in data:
                raise f.fail("kinds", "the 6dof example has its own joint kinds: leave 'kinds' out")
            if (jl := f.pairs("joint_limits", 6)) is not None:
                kw["joint_limits"] = jl
            if (r := f.number("radius", positive=True)) is not None:
                kw["radius"] = r
            try:
                return SerialArm.example_6dof(name, **kw, **common)
            except ValidationError as exc:
                raise ValidationError(f"{where}: {exc}") from None
        dh = data.get("dh")
        if not isinstance(dh, list) or not dh:
            raise f.fail("dh", f"expected rows of [a, alpha, d, offset], got {dh!r}")
        for i, row in enumerate(dh):
            _Fields({"row": row}, f"{where}.dh[{i}]").numbers(
                "row", 4, bounds=_META["serial"]["dh"]
            )
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
