"""Run every benchmark: ``python -m benchmarks [--quick]`` (``make bench``)."""

from __future__ import annotations

import sys

from benchmarks import (
    bench_bounds,
    bench_cells,
    bench_fjsp,
    bench_fjsp_seeds,
    bench_generated,
    bench_geometry,
    bench_grid,
    bench_kernel,
    bench_lines,
    bench_longrun,
    bench_network,
    bench_oracle,
    bench_outside,
    bench_policies,
    bench_polish,
    bench_relaxed,
    bench_resolve,
    bench_resolve_loop,
    bench_scale,
    bench_setups,
    bench_sim,
    bench_simkernel,
    bench_small,
    bench_sweep,
    bench_urdf,
    bench_zones,
    gap_anatomy,
)


def main() -> None:
    quick = ["--quick"] if "--quick" in sys.argv[1:] else []
    for mod in (
        bench_kernel,
        bench_oracle,
        bench_zones,
        bench_geometry,
        bench_cells,
        bench_grid,
        bench_urdf,
        bench_resolve,
        bench_resolve_loop,
        bench_sim,
        bench_policies,
        bench_simkernel,
        bench_network,
        bench_scale,
        gap_anatomy,
        bench_longrun,
        bench_relaxed,
        bench_bounds,
        bench_generated,
        bench_setups,
        bench_lines,
        bench_outside,
        bench_polish,
        bench_small,
        bench_fjsp,
        bench_fjsp_seeds,
        bench_sweep,
    ):
        print(f"== {mod.__name__}", flush=True)
        sys.argv = [mod.__name__, *quick]
        mod.main()


if __name__ == "__main__":
    main()
