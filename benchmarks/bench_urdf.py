"""URDF arms: compile time, kinematics, fitted capsules and the capsule check
against FCL on the meshes, side by side in one run.

``python -m benchmarks.bench_urdf [--quick]`` writes ``results/urdf.md`` and
``results/urdf.json``:

1. Compile time per cell and per mode (``workcell.compile_cell``),
   cold (first in the process) and the best of several warm compiles (wall
   and CPU time), for ``urdf_cell`` (two UR5 and a Panda from URDF) next to
   ``scara4`` and ``cell8`` (whose serial arms are DH chains) as yardsticks.
2. Kinematics per call (CPU time): forward kinematics of a batch and IK of
   one pose, the UR5 (URDF, compiled chain) next to the built-in DH 6-DOF arm.
3. The fitted capsules per link of the UR5 and the Panda: coverage (share of
   sampled mesh surface points inside the capsule: must be 100 %) and the
   volume overshoot (capsule volume over the mesh's convex hull volume, and
   over the mesh's own volume where the mesh is closed).
4. Two UR5 facing each other 0.6 m apart, seeded uniform random joints: the
   compiled capsule check (``capsules_touch``, the sweep's state test) next
   to FCL on the meshes (BVH objects, ``CollisionWorld.add_arm_meshes``):
   how often the capsules flag a contact the meshes do not (the price of
   being conservative), how often the reverse (must be never), and the CPU
   time per state of each.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from benchmarks.common import output_dir, write
from multiarm.errors import Unreachable
from workcell import compile_cell, load_example


def compile_rows(cells: tuple[tuple[str, int], ...]) -> list[dict[str, Any]]:
    """Per cell: one cold compile, then ``warm`` warm ones; the best warm
    wall time and the best warm CPU time of this process (the machine may be
    shared: CPU time is the steadier figure)."""
    rows = []
    for name, warm in cells:
        cell = load_example(name)
        t0 = time.perf_counter()
        cc = compile_cell(cell)
        cold = time.perf_counter() - t0
        walls, cpus = [], []
        for _ in range(warm):
            t0, c0 = time.perf_counter(), time.process_time()
            compile_cell(cell)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        m = cc.problem.n_modes
        rows.append(
            {
                "cell": name,
                "arm kinds": ", ".join(sorted({a.kind for a in cell.arms})),
                "modes": m,
                "cold (s)": round(cold, 2),
                "warm compiles": warm,
                "warm, best (s)": round(min(walls), 3),
                "per mode, warm best (ms)": round(1000 * min(walls) / m, 1),
                "per mode, warm CPU best (ms)": round(1000 * min(cpus) / m, 1),
            }
        )
    return rows


def kinematics_rows(seed: int, batch: int, poses: int) -> list[dict[str, Any]]:
    from workcell.arms import SerialArm
    from workcell.arms.urdf import UR5, UrdfArm

    rng = np.random.default_rng(seed)
    rows = []
    for label, arm in (
        ("UR5 (URDF)", UrdfArm("ur5", UR5, tool_link="tool0")),
        ("6-DOF DH (cell8's serial)", SerialArm.example_6dof("dh")),
    ):
        lo, hi = arm.joint_limits[:, 0], arm.joint_limits[:, 1]
        qs = lo + (hi - lo) * rng.random((batch, arm.dof))
        arm.frames(qs[:2])
        best = np.inf
        for _ in range(5):
            t0 = time.process_time()
            arm.frames(qs)
            best = min(best, time.process_time() - t0)
        targets = arm.fk(qs[:poses])
        hints = np.clip(qs[:poses] + rng.normal(0, 0.1, (poses, arm.dof)), lo, hi)
        arm.ik(targets[0], hints[0])
        t0 = time.process_time()
        ok = 0
        for t, h in zip(targets, hints, strict=True):
            try:
                arm.ik(t, h)
                ok += 1
            except Unreachable:  # counted as a miss
                pass
        ik = (time.process_time() - t0) / poses
        rows.append(
            {
                "arm": label,
                "frames per config, CPU (us)": round(1e6 * best / batch, 2),
                "IK per pose, CPU (us)": round(1e6 * ik, 1),
                "IK solved": f"{ok}/{poses}",
            }
        )
    return rows


def capsule_rows(seed: int, samples: int) -> list[dict[str, Any]]:
    import trimesh

    from workcell.arms.capsules import FittedCapsule, capsule_contains, capsule_volume
    from workcell.arms.urdf import PANDA, UR5, UrdfArm

    rows = []
    for robot, arm in (
        ("UR5", UrdfArm("ur5", UR5, tool_link="tool0")),
        ("Panda", UrdfArm("panda", PANDA, tool_link="panda_hand_tcp")),
    ):
        for shape, mesh, fitted in zip(arm.shapes, arm.meshes, arm.model.hulls, strict=True):
            off = np.asarray(shape.offset)
            half = shape.size[1] / 2 if shape.kind == "capsule" else 0.0
            cap = FittedCapsule(
                off[:3, 3] - half * off[:3, 2], off[:3, 3] + half * off[:3, 2], shape.size[0]
            )
            tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
            pts, _ = trimesh.sample.sample_surface(tm, samples, seed=seed)
            inside = float(np.mean(capsule_contains(cap, np.vstack([pts, mesh.vertices]))))
            hull = trimesh.convex.convex_hull(fitted).volume
            vol = capsule_volume(cap)
            closed = tm.is_watertight and tm.volume > 0
            rows.append(
                {
                    "robot": robot,
                    "link": shape.name,
                    "radius (mm)": round(1000 * shape.size[0], 1),
                    "length (mm)": round(1000 * half * 2, 1),
                    "coverage": f"{inside:.2%}",
                    "capsule / hull volume": round(vol / hull, 2),
                    "capsule / mesh volume": round(vol / tm.volume, 2) if closed else "open mesh",
                }
            )
    return rows


def agreement(seed: int, parks: int, states: int) -> dict[str, Any]:
    from workcell.arms.urdf import UR5, UrdfArm
    from workcell.geometry import CollisionWorld
    from workcell.geometry._zone_sweep_jit import capsules_touch
    from workcell.geometry.zone_sweep import _segments, _shape_capsules

    a = UrdfArm("a", UR5, tool_link="tool0")
    base_b = np.diag([-1.0, -1.0, 1.0, 1.0])
    base_b[0, 3] = 0.6
    b = UrdfArm("b", UR5, tool_link="tool0", base=base_b)
    world = CollisionWorld()
    world.add_arm_meshes(a, "a")
    world.add_arm_meshes(b, "b")
    local_a, rad_a = _shape_capsules(a.shapes)
    local_b, rad_b = _shape_capsules(b.shapes)
    rng = np.random.default_rng(seed)
    lo, hi = a.joint_limits[:, 0], a.joint_limits[:, 1]
    both = caps_only = mesh_only = neither = 0
    t_caps = t_mesh = 0.0
    for _ in range(parks):
        qb = lo + (hi - lo) * rng.random(b.dof)
        qa = lo + (hi - lo) * rng.random((states, a.dof))
        b0, b1 = _segments(b, qb[None], local_b)
        world.set_group_transforms("b", b.mesh_transforms(qb[None])[0])
        a0, a1 = _segments(a, qa[:2], local_a)
        capsules_touch(a0, a1, rad_a, b0[0], b1[0], rad_b, 0.0)  # warm
        t0 = time.process_time()
        a0, a1 = _segments(a, qa, local_a)
        caps = capsules_touch(a0, a1, rad_a, b0[0], b1[0], rad_b, 0.0)
        t_caps += time.process_time() - t0
        tfs = a.mesh_transforms(qa)
        t0 = time.process_time()
        mesh = np.empty(states, dtype=bool)
        for i in range(states):
            world.set_group_transforms("a", tfs[i])
            mesh[i] = world.collide("a", "b")
        t_mesh += time.process_time() - t0
        both += int(np.sum(caps & mesh))
        caps_only += int(np.sum(caps & ~mesh))
        mesh_only += int(np.sum(~caps & mesh))
        neither += int(np.sum(~caps & ~mesh))
    n = parks * states
    return {
        "states": n,
        "both touch": both,
        "capsules only (conservative)": caps_only,
        "meshes only (must be 0)": mesh_only,
        "neither": neither,
        "capsule false alarms / capsule contacts": f"{caps_only / max(both + caps_only, 1):.1%}",
        "capsule check, CPU (us/state)": round(1e6 * t_caps / n, 2),
        "FCL meshes, CPU (us/state)": round(1e6 * t_mesh / n, 1),
    }


def _table(rows: list[dict[str, Any]]) -> str:
    cols = list(rows[0])
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    out += ["| " + " | ".join(str(r[c]) for c in cols) + " |" for r in rows]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="tiny sizes, into a temporary directory")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    seed = args.seed
    cells = (("urdf_cell", 1),) if args.quick else (("urdf_cell", 5), ("scara4", 5), ("cell8", 2))
    comp = compile_rows(cells)
    kin = kinematics_rows(seed, 100 if args.quick else 10000, 5 if args.quick else 200)
    caps = capsule_rows(seed, 200 if args.quick else 5000)
    agree = agreement(seed, 2 if args.quick else 20, 50 if args.quick else 1000)
    cmd = "python -m benchmarks.bench_urdf" + (" --quick" if args.quick else "")
    text = (
        "# URDF arms\n\n"
        f"Reproduce: `{cmd}` (seed {seed}; one run, side by side). CPU times are\n"
        "this process's own, steadier than wall times on a shared machine.\n\n"
        "## Compile time\n\n" + _table(comp) + "\n"
        "## Kinematics per call (CPU time)\n\n" + _table(kin) + "\n"
        "## Fitted capsules (conservative: coverage must be 100 %)\n\n" + _table(caps) + "\n"
        "## Capsule check against FCL on the meshes (two UR5, 0.6 m apart)\n\n" + _table([agree])
    )
    path = write(
        "urdf",
        {
            "seed": seed,
            "compile": comp,
            "kinematics": kin,
            "capsules": caps,
            "agreement": agree,
        },
        text,
        output_dir(args.quick),
    )
    print(text)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
