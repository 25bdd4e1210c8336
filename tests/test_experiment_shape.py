"""One shape for every experiment (issue 35): a spec, ``run(spec) -> typed result``, a writer and its own
command, recorded in :data:`spectracam.experiments.EXPERIMENTS` and held to the code here: every part
resolves, the registry and the command line name the same commands, each run's return annotation is its
result's TypedDict, and, where a run is cheap enough to make here, the dict it returns has exactly the
TypedDict's keys (so the type fails when the run changes)."""
import subprocess
import sys
import typing

import click
import pytest

from spectracam.cli import main as cli
from spectracam.experiments import EXPERIMENTS, Experiment, resolve

#: The commands of cli.py's LAZY table that are not experiments: the single stages and the viewer.
SINGLE_STAGE = {"capture", "inspect", "render", "score", "simulate", "view"}


def _keys(td) -> set:
    return set(td.__required_keys__ | td.__optional_keys__)


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_every_part_resolves(name):
    e = EXPERIMENTS[name]
    assert e.name == name
    parts = {field: e.part(field) for field in e.refs()}
    assert isinstance(parts["command"], click.Command) and parts["command"].name == name
    assert all(isinstance(resolve(c), click.Command) for c in e.other_commands)
    assert typing.is_typeddict(parts["result"]), e.result
    typing.get_type_hints(parts["result"])   # every value type names something real
    assert callable(parts["run"])
    assert e.spec is None or isinstance(parts["spec"], type)
    assert e.load is None or callable(parts["load"])
    assert (e.writer is None) == e.writes_as_it_runs and (e.writer is None or callable(parts["writer"]))
    assert e.package == f"spectracam.experiments.{name.replace('-', '_')}"
    assert e.run.startswith(e.package + ".") and e.result.partition(":")[0] == e.run.partition(":")[0]


def test_an_experiment_has_a_writer_or_writes_as_it_runs():
    with pytest.raises(ValueError, match="a writer, or writes_as_it_runs"):
        Experiment("x", None, None, "m:run", "m:Result", None, "m:cmd")
    assert [n for n, e in EXPERIMENTS.items() if e.writes_as_it_runs] == ["sweep"]


def test_the_registry_and_the_command_line_name_the_same_commands():
    lazy = {name: f"{module}:{attr}" for name, (module, attr) in cli.LAZY.items()}
    assert SINGLE_STAGE <= set(lazy)
    for name, e in EXPERIMENTS.items():
        assert lazy.get(name) == e.command, name
    registered = {c for e in EXPERIMENTS.values() for c in (e.command, *e.other_commands)}
    assert {ref for name, ref in lazy.items() if name not in SINGLE_STAGE} == registered
    assert not any(lazy[name] in registered for name in SINGLE_STAGE)


@pytest.mark.parametrize("name", list(EXPERIMENTS))
def test_each_run_returns_its_experiments_typeddict(name):
    e = EXPERIMENTS[name]
    run = e.part("run")
    returned = eval(run.__annotations__["return"], run.__globals__)   # the one annotation, not the parameters'
    if typing.get_origin(returned) is tuple:   # paper: (result, cases, cubes)
        returned = typing.get_args(returned)[0]
    assert returned is e.part("result")


def test_the_registry_imports_no_experiment():
    """The parts are strings: importing the registry (the command line's start-up does) loads no experiment."""
    code = ("import sys, spectracam.experiments as x; assert len(x.EXPERIMENTS) == 13; "
            "print(sorted(m for m in sys.modules if m.startswith('spectracam.experiments.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_the_emva_result_has_its_typeddicts_keys():
    from spectracam.camera import CameraSpec
    from spectracam.experiments.emva.experiment import EmvaResult, EmvaSetup, run_emva

    assert set(run_emva(CameraSpec(), EmvaSetup(width=64, height=64))) == _keys(EmvaResult)


def test_the_validate_result_has_its_typeddicts_keys():
    from spectracam.experiments.validate.experiment import ValidateResult, run_validate

    result = run_validate("analytic")
    assert set(result) == _keys(ValidateResult)   # real_camera_data too: the shipped cameras, not a user's


def test_the_sweep_result_has_its_typeddicts_keys(tmp_path):
    from pathlib import Path

    from spectracam.experiments.sweep.experiment import SweepResult, load_sweep, run_sweep

    base = (Path(__file__).parent.parent / "scenes" / "blackbody_5000K.toml").resolve()
    p = tmp_path / "sweep.toml"
    p.write_text(f'base_scene = "{base}"\nrenderer = "analytic"\ntrials = 1\nmetrics = ["delta_e_mean"]\n'
                 '[scene]\nimage = { width = 96, height = 72 }\n[axes]\n"illuminant.temperature_K" = [5000]\n')
    assert set(run_sweep(load_sweep(p), tmp_path / "out", serial=True, progress=False)) == _keys(SweepResult)


def test_the_registrys_doctest():
    import doctest

    import spectracam.experiments

    result = doctest.testmod(spectracam.experiments)
    assert result.attempted > 0 and result.failed == 0
