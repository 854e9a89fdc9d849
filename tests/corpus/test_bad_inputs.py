"""Our own corpus of bad inputs through the command line: cell files, fault
files, sweep files and command-line arguments.

Each case writes its input files into a fresh folder, puts an output that
already exists where the command would write (a run folder holding a
``tasks.csv``, a sweep results file), runs ``multiarm ...`` and asserts

* the exit status (1 for an error of ours, 2 for an argument the parser
  refuses),
* that the message names the file and the field (or the option),
* that the existing output survives byte for byte,
* and that nothing was compiled, solved or run: the commands run with their
  progress on (one line a step when stderr is not a terminal, as here), and
  the only line printed is the error, so no step (compile, solve, simulate,
  a sweep's runs) began; and every case fails within seconds (:data:`QUICK`).

The corpus of problem files is ``tests/scheduler/test_corpus.py``, the SDL
one ``tests/zones/malformed/``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from workcell.cli import main

QUICK = 20.0
"""Seconds a refused case may take (loading a built-in cell included; no
case compiles)."""

KEEP = b"an earlier result that must survive\n"

CELL = """\
name = "numbers"
zones = "builtin:supersigma"
tasks = "builtin:supersigma"

[compile]
padding = 0.005
grid = 0.3

[arms.g]
type = "gantry"
base = [0.0, 0.0, 0.0, 0.0]
rails = { x = [0.0, 1.85], y = [0.0, 1.2], z = [0.0, 0.6] }
height = 0.8
payload = 2.0
capabilities = ["gripper", "force_sensor", "object_detector", "tool_changer"]
tools = ["screwdriver"]

[arms.g.stepper]
step_length = 0.0000375
max_rate = 15000.0

[arms.s]
type = "scara"
base = [-0.5, -0.5, 0.0, 0.7853981633974483]
link_lengths = [0.45, 0.4]
max_velocity = [3.0, 4.0, 1.0, 6.0]
max_acceleration = [10.0, 15.0, 5.0, 30.0]
radius = 0.05
payload = 3.0
"""

SWEEP = """\
[sweep]
name = "s"
repetitions = 1

[[instances]]
kind = "generated"
sizes = [[2, 4, 1, 0]]
seeds = [0]

[[solvers]]
solver = "greedy"
time_limit = 1.0
"""


def _cell(old: str, new: str) -> str:
    assert old in CELL, old
    return CELL.replace(old, new)


def _sweep(old: str, new: str) -> str:
    assert old in SWEEP, old
    return SWEEP.replace(old, new)


@dataclass(frozen=True)
class Case:
    """One bad input: files to write, the command (``{NAME}`` is the path of
    file NAME, ``{OUT}`` the output), the exit status and words of the message."""

    id: str
    argv: tuple[str, ...]
    files: dict[str, str | bytes] = field(default_factory=dict)
    status: int = 1
    words: tuple[str, ...] = ()


def _simulate_cell(id: str, text: str | bytes, *words: str) -> Case:
    return Case(id, ("simulate", "{c.toml}", "--out", "{OUT}"), {"c.toml": text}, 1, words)


def _faults(id: str, text: str, *words: str, name: str = "f.toml") -> Case:
    return Case(
        id,
        ("simulate", "supersigma", "--faults", "{" + name + "}", "--out", "{OUT}"),
        {name: text},
        1,
        words,
    )


def _sweep_case(id: str, text: str, *words: str, extra: tuple[str, ...] = ()) -> Case:
    return Case(
        id,
        ("sweep", "{s.toml}", "--out", "{OUT}", *extra),
        {"s.toml": text},
        1,
        words,
    )


CASES: list[Case] = [
    # ------------------------------------------------------------ cell files
    _simulate_cell(
        "cell-link-1e300",
        _cell("link_lengths = [0.45, 0.4]", "link_lengths = [1e300, 0.4]"),
        "c.toml: arms.s.link_lengths",
        "out of range",
    ),
    _simulate_cell(
        "cell-velocity-1e-300",
        _cell("max_velocity = [3.0,", "max_velocity = [1e-300,"),
        "c.toml: arms.s.max_velocity",
    ),
    _simulate_cell(
        "cell-acceleration-1e300",
        _cell("max_acceleration = [10.0,", "max_acceleration = [1e300,"),
        "c.toml: arms.s.max_acceleration",
    ),
    _simulate_cell(
        "cell-step-length-1e-300",
        _cell("step_length = 0.0000375", "step_length = 1e-300"),
        "c.toml: arms.g.stepper.step_length",
    ),
    _simulate_cell(
        "cell-rate-1e300",
        _cell("max_rate = 15000.0", "max_rate = 1e300"),
        "c.toml: arms.g.stepper.max_rate",
    ),
    _simulate_cell(
        "cell-radius-1e300",
        _cell("radius = 0.05", "radius = 1e300"),
        "c.toml: arms.s.radius",
    ),
    _simulate_cell(
        "cell-base-1e300",
        _cell("base = [0.0, 0.0, 0.0, 0.0]", "base = [1e300, 0.0, 0.0, 0.0]"),
        "c.toml: arms.g.base",
    ),
    _simulate_cell(
        "cell-rail-200m",
        _cell("x = [0.0, 1.85]", "x = [0.0, 200.0]"),
        "c.toml: arms.g.rails",
    ),
    _simulate_cell(
        "cell-payload-inf",
        _cell("payload = 3.0", "payload = inf"),
        "c.toml: arms.s.payload",
    ),
    _simulate_cell(
        "cell-height-nan",
        _cell("height = 0.8", "height = nan"),
        "c.toml: arms.g.height",
    ),
    _simulate_cell(
        "cell-grid-1e300",
        _cell("grid = 0.3", "grid = 1e300"),
        "c.toml: compile.grid",
    ),
    _simulate_cell(
        "cell-padding-denormal",
        _cell("padding = 0.005", "padding = 1e-310"),
        "c.toml: compile.padding",
    ),
    _simulate_cell("cell-empty", "", "c.toml"),
    _simulate_cell(
        "cell-latin1", CELL.replace("numbers", "zahlen-\xfc").encode("latin-1"), "c.toml"
    ),
    _simulate_cell("cell-toml-syntax", CELL.replace("[arms.s]", "[arms.s"), "c.toml:"),
    _simulate_cell(
        "cell-unknown-key",
        _cell("radius = 0.05", "raduis = 0.05"),
        "c.toml: arms.s",
        "raduis",
    ),
    _simulate_cell(
        "cell-empty-arm-name",
        CELL.replace("[arms.s]", '[arms.""]').replace("[arms.g.stepper]", "[arms.g.stepper]"),
        "c.toml",
    ),
    # ----------------------------------------------------------- fault files
    _faults(
        "faults-unknown-arm",
        '[[faults]]\nkind = "arm_failure"\narm = "sx"\nat = 3.0\n',
        "f.toml: faults[0].arm: unknown arm 'sx'",
        "known: left, right",
    ),
    _faults(
        "faults-misspelt-message-kind",
        '[[faults]]\nkind = "message_loss"\nprobability = 0.2\nkinds = ["zone_reqest"]\n',
        "f.toml: faults[0].kinds[0]: unknown message kind 'zone_reqest'",
        "did you mean 'zone_request'?",
    ),
    _faults(
        "faults-arm-fails-twice",
        '[[faults]]\nkind = "arm_failure"\narm = "left"\nat = 3.0\n'
        '[[faults]]\nkind = "arm_failure"\narm = "left"\nat = 9.0\n',
        "f.toml: faults[1].arm: arm 'left' already fails",
    ),
    _faults(
        "faults-unknown-part",
        '[[faults]]\nkind = "late_part"\npart = "gear"\ndelay = 3.0\n',
        "f.toml: faults[0].part: unknown part 'gear'",
    ),
    _faults(
        "faults-unknown-zone",
        '[[faults]]\nkind = "activate_zones"\nat = 1.0\nzones = ["fixture", "moon"]\n',
        "f.toml: faults[0].zones[1]: unknown zone 'moon'",
    ),
    _faults(
        "faults-estop-1e300",
        '[[faults]]\nkind = "emergency_stop"\nat = 1e300\nduration = 1.0\n',
        "f.toml",
        "f.toml: faults[0].at: must be in [0, 1e+06] seconds",
    ),
    _faults(
        "faults-estop-duration-1e300",
        '[[faults]]\nkind = "emergency_stop"\nat = 1.0\nduration = 1e300\n',
        "f.toml: faults[0].duration: must be in [0, 1e+06] seconds",
    ),
    _faults(
        "faults-loss-0.999999",
        '[[faults]]\nkind = "message_loss"\nprobability = 0.999999\n',
        "f.toml: faults[0].probability: must be in [0, 0.999]",
    ),
    _faults(
        "faults-unknown-kind",
        '[[faults]]\nkind = "meteor"\n',
        "f.toml",
        "faults[0].kind: unknown fault kind 'meteor'",
    ),
    _faults("faults-toml-syntax", '[[faults]\nkind = "crash"\n', "f.toml:1:"),
    _faults(
        "faults-json-unknown-arm",
        '[{"kind": "crash", "arm": "middle", "at": 2.0}]',
        "f.json: faults[0].arm: unknown arm 'middle'",
        name="f.json",
    ),
    _faults(
        "faults-servo-axis",
        '[[faults]]\nkind = "lost_sync"\narm = "left"\naxis = 9\nat = 2.0\n',
        "f.toml: faults[0].axis: arm 'left' has axes",
    ),
    # ----------------------------------------------------------- sweep files
    _sweep_case(
        "sweep-repetitions-1e9",
        _sweep("repetitions = 1", "repetitions = 1000000000"),
        "s.toml: sweep.repetitions",
        "<= 100000",
    ),
    _sweep_case(
        "sweep-runs-over-cap",
        _sweep("seeds = [0]", "seeds = [" + ", ".join(map(str, range(2000))) + "]").replace(
            "repetitions = 1", "repetitions = 60"
        ),
        "s.toml: sweep.repetitions",
        "more than 100000",
    ),
    _sweep_case(
        "sweep-generated-1e7-tasks",
        _sweep("sizes = [[2, 4, 1, 0]]", "sizes = [[2, 10000000, 1, 0]]"),
        "s.toml: instances[0].sizes[0][1]",
    ),
    _sweep_case(
        "sweep-time-limit-1e300",
        _sweep("time_limit = 1.0", "time_limit = 1e300"),
        "s.toml: solvers[0].time_limit",
    ),
    _sweep_case(
        "sweep-time-limit-1e-300",
        _sweep("time_limit = 1.0", "time_limit = 1e-300"),
        "s.toml: solvers[0].time_limit",
    ),
    _sweep_case(
        "sweep-seed-2e63",
        _sweep("seeds = [0]", "seeds = [9223372036854775807]"),
        "s.toml: instances[0].seeds[0]: expected an integer >= 0 and <= 4611686018427387904",
    ),
    _sweep_case(
        "sweep-campaign-1e9-episodes",
        '[sweep]\nname = "c"\n[[instances]]\nkind = "campaign"\ncells = ["supersigma"]\n'
        "episodes = 1000000000\n",
        "s.toml: instances[0].episodes",
    ),
    _sweep_case(
        "sweep-unknown-solver",
        _sweep('solver = "greedy"', 'solver = "gredy"'),
        "s.toml: solvers[0].solver",
    ),
    _sweep_case("sweep-toml-syntax", SWEEP.replace("[[solvers]]", "[[solvers]"), "s.toml:"),
    _sweep_case(
        "sweep-dask-address",
        SWEEP,
        "--dask-address",
        extra=("--dask-address", "tcp//host"),
    ),
    Case(
        "sweep-out-directory",
        ("sweep", "{s.toml}", "--out", "{TMP}"),
        {"s.toml": SWEEP},
        1,
        ("--out", "is a directory; give a results file such as"),
    ),
    Case(
        "sweep-out-under-a-file",
        ("sweep", "{s.toml}", "--out", "{s.toml}/results.parquet"),
        {"s.toml": SWEEP},
        1,
        ("--out", "cannot create the folder of", "s.toml/results.parquet"),
    ),
    # --------------------------------------------------------- command lines
    Case(
        "cli-out-is-a-file",
        ("simulate", "supersigma", "--out", "{f.txt}"),
        {"f.txt": "not a folder\n"},
        words=("--out", "f.txt' is not a directory"),
    ),
    Case(
        "cli-time-limit-nan",
        ("simulate", "supersigma", "--time-limit", "nan", "--out", "{OUT}"),
        words=("--time-limit",),
    ),
    Case(
        "cli-time-limit-negative",
        ("simulate", "supersigma", "--time-limit", "-1", "--out", "{OUT}"),
        words=("--time-limit",),
    ),
    Case(
        "cli-tick-zero",
        ("simulate", "supersigma", "--tick", "0", "--out", "{OUT}"),
        words=("--tick",),
    ),
    Case(
        "cli-frames-negative",
        ("simulate", "supersigma", "--frames", "-5", "--out", "{OUT}"),
        words=("--frames",),
    ),
    Case(
        "cli-network-unknown",
        ("simulate", "supersigma", "--network", "carrier-pigeon", "--out", "{OUT}"),
        words=("--network", "carrier-pigeon"),
    ),
    Case(
        "cli-evaluations-zero",
        ("simulate", "supersigma", "--evaluations", "0", "--out", "{OUT}"),
        words=("--evaluations",),
    ),
    Case(
        "cli-faults-missing",
        ("simulate", "supersigma", "--faults", "{TMP}/nope.toml", "--out", "{OUT}"),
        words=("--faults", "nope.toml"),
    ),
    Case(
        "cli-faults-suffix",
        ("simulate", "supersigma", "--faults", "{f.yaml}", "--out", "{OUT}"),
        {"f.yaml": "faults: []\n"},
        words=("--faults", "f.yaml"),
    ),
    Case("cli-cell-unknown", ("simulate", "supercell", "--out", "{OUT}"), words=("supercell",)),
    Case(
        "cli-solver-unknown",
        ("simulate", "supersigma", "--solver", "magic", "--out", "{OUT}"),
        status=2,
        words=("--solver", "magic"),
    ),
    Case(
        "cli-time-limit-text",
        ("simulate", "supersigma", "--time-limit", "soon", "--out", "{OUT}"),
        status=2,
        words=("--time-limit", "soon"),
    ),
]


def _argv(case: Case, tmp: Path, out: Path) -> list[str]:
    names = {name: str(tmp / name) for name in case.files}
    argv = []
    for a in case.argv:
        a = a.replace("{OUT}", str(out)).replace("{TMP}", str(tmp))
        for name, path in names.items():
            a = a.replace("{" + name + "}", path)
        argv.append(a)
    return argv


def test_the_corpus_covers_every_family() -> None:
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    for family, least in (("cell-", 15), ("faults-", 12), ("sweep-", 10), ("cli-", 10)):
        assert sum(i.startswith(family) for i in ids) >= least, family


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_a_bad_input_is_refused_early_by_name_and_spares_existing_outputs(
    case: Case, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for name, text in case.files.items():
        data = text.encode("utf-8") if isinstance(text, str) else text
        (tmp_path / name).write_bytes(data)
    if case.argv[0] == "sweep":
        out = tmp_path / "results.parquet"
        out.write_bytes(KEEP)
        kept = out
    else:
        out = tmp_path / "run"
        out.mkdir()
        kept = out / "tasks.csv"
        kept.write_bytes(KEEP)
    before = sorted(p.name for p in out.iterdir()) if out.is_dir() else None
    t0 = time.perf_counter()
    if case.status == 2:
        with pytest.raises(SystemExit) as info:
            main(_argv(case, tmp_path, out))
        status = info.value.code
    else:
        status = main(_argv(case, tmp_path, out))
    seconds = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert status == case.status, err
    for words in case.words:
        assert words in err, (words, err)
    assert "Traceback" not in err
    if case.status == 1:  # one line, the error: no progress line, so no step began
        assert len(err.strip().splitlines()) == 1 and err.startswith("error: "), err
    assert kept.read_bytes() == KEEP
    if before is not None:
        assert sorted(p.name for p in out.iterdir()) == before
    assert seconds < QUICK, f"{case.id}: {seconds:.1f} s: refused after long work?"
