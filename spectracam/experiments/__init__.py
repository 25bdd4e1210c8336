"""The experiments: one folder per question the simulator answers, each with its ``experiment.py`` (the
spec, the run, its result and writers) and its ``command.py`` (the command line that parses into them).

Every experiment has one shape (issue 35), recorded in :data:`EXPERIMENTS`: a spec (a frozen class, and the
function that makes one from a file and ``--set``), ``run(spec, …) -> result`` whose result is a
:class:`typing.TypedDict` naming the top-level keys of the dict it returns, a writer that turns that dict
into the output files (``results.json`` or the experiment's own JSON, a report, figures), and its click
command.  The parts are ``"module:attr"`` strings, imported only when :meth:`Experiment.part` asks for one,
so the command line starts without importing any experiment.

>>> from spectracam.experiments import EXPERIMENTS
>>> EXPERIMENTS["emva"].run
'spectracam.experiments.emva.experiment:run_emva'
"""
from __future__ import annotations

from dataclasses import dataclass
from importlib import import_module
from typing import TYPE_CHECKING, Any

from spectracam.core.registry import Registry

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["EXPERIMENTS", "Experiment", "experiment_names", "resolve"]


def experiment_names(package: str) -> Callable[[str], Any]:
    """A package face's ``__getattr__`` (PEP 562) that finds a name in the package's ``experiment`` module on
    first use: ``spectracam.experiments.paper.run_paper`` (the module's name before issue 35) stays valid,
    and the command's start-up does not import the experiment before it runs.

    Parameters
    ----------
    package : str
        The package's dotted name (``"spectracam.experiments.paper"``).

    Returns
    -------
    callable
        ``__getattr__(name)``: the attribute of ``PACKAGE.experiment``; AttributeError for a dunder name.
    """

    def __getattr__(name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(import_module(f"{package}.experiment"), name)

    return __getattr__


def resolve(ref: str) -> Any:
    """The object a ``"module:attr"`` reference names (as :attr:`spectracam.cli._Group.LAZY` does).

    Parameters
    ----------
    ref : str
        ``"module:attr"``.

    Returns
    -------
    object
        The attribute, its module imported now.
    """
    module, _, attr = ref.partition(":")
    return getattr(import_module(module), attr)


@dataclass(frozen=True)
class Experiment:
    """One experiment's parts, each a ``"module:attr"`` reference (:func:`resolve`).

    ``spec``: the class of its settings (None: validate's run takes its settings as arguments — the renderer
    and, optionally, the keyword arguments of ``user_camera``); ``load``: the function that makes the spec from
    a file and ``--set`` (None: the command builds it from its options); ``run``: the run; ``result``: the
    TypedDict of the dict it returns (paper's run returns ``(result, cases, cubes)``: the first is typed, the
    cases and cubes go to the writer beside it); ``writer``: writes the result's files (None with
    ``writes_as_it_runs``: sweep appends each cell to its journal as it finishes and writes its tables at the
    end, and its result is the run's timing figures); ``command``: its click command;
    ``other_commands``: the other commands its ``command.py`` holds (sweep's ``plot-sweep`` reads a finished
    sweep, validate's ``cameras`` lists the library it checks)."""

    name: str
    spec: str | None
    load: str | None
    run: str
    result: str
    writer: str | None
    command: str
    other_commands: tuple[str, ...] = ()
    writes_as_it_runs: bool = False

    def __post_init__(self):
        if (self.writer is None) != self.writes_as_it_runs:
            raise ValueError(f"experiment {self.name!r}: a writer, or writes_as_it_runs, not both or neither")

    @property
    def package(self) -> str:
        """``spectracam.experiments.<folder>``: where its command.py and experiment.py live."""
        return self.command.partition(":")[0].rpartition(".")[0]

    def refs(self) -> dict[str, str]:
        """Every part that is set, by field name (``other_commands`` as ``other_commands[i]``)."""
        out = {f: getattr(self, f) for f in ("spec", "load", "run", "result", "writer", "command")
               if getattr(self, f) is not None}
        out.update({f"other_commands[{i}]": c for i, c in enumerate(self.other_commands)})
        return out

    def part(self, field: str) -> Any:
        """The object one part names, imported now (``EXPERIMENTS["emva"].part("run")`` is ``run_emva``).

        Parameters
        ----------
        field : str
            A key of :meth:`refs` (``"run"``, ``"writer"``, ``"other_commands[0]"``, …).

        Returns
        -------
        object
            The class, function or click command.
        """
        return resolve(self.refs()[field])


#: Every experiment by its command's name (:attr:`spectracam.cli._Group.LAZY` holds the same commands).
EXPERIMENTS: Registry[Experiment] = Registry("experiment", "experiment")

_X = "spectracam.experiments"
for _e in (
    Experiment("paper", spec=f"{_X}.paper.experiment:PaperExperiment", load=f"{_X}.paper.experiment:load_experiment",
               run=f"{_X}.paper.experiment:run_paper", result=f"{_X}.paper.experiment:PaperResult",
               writer=f"{_X}.paper.report:write_paper_outputs", command=f"{_X}.paper.command:paper_cmd"),
    Experiment("consistency", spec=f"{_X}.paper.experiment:PaperExperiment",
               load=f"{_X}.paper.experiment:load_experiment", run=f"{_X}.consistency.experiment:run_consistency",
               result=f"{_X}.consistency.experiment:ConsistencyResult",
               writer=f"{_X}.consistency.experiment:write_consistency_outputs",
               command=f"{_X}.consistency.command:consistency_cmd"),
    Experiment("emva", spec=f"{_X}.emva.experiment:EmvaSetup", load=None, run=f"{_X}.emva.experiment:run_emva",
               result=f"{_X}.emva.experiment:EmvaResult", writer=f"{_X}.emva.experiment:write_emva_outputs",
               command=f"{_X}.emva.command:emva_cmd"),
    Experiment("architectures", spec=f"{_X}.architectures.experiment:ArchitecturesRun",
               load=f"{_X}.paper.experiment:load_experiment", run=f"{_X}.architectures.experiment:run_architectures",
               result=f"{_X}.architectures.experiment:ArchitecturesResult",
               writer=f"{_X}.architectures.experiment:write_architectures_outputs",
               command=f"{_X}.architectures.command:architectures_cmd"),
    Experiment("design", spec=f"{_X}.design.spec:DesignSpec", load=f"{_X}.design.spec:load_design",
               run=f"{_X}.design.run:run_design", result=f"{_X}.design.run:DesignResult",
               writer=f"{_X}.design.report:write_design_outputs", command=f"{_X}.design.command:design_cmd"),
    Experiment("sweep", spec=f"{_X}.sweep.experiment:Sweep", load=f"{_X}.sweep.experiment:load_sweep",
               run=f"{_X}.sweep.experiment:run_sweep", result=f"{_X}.sweep.experiment:SweepResult",
               writer=None, writes_as_it_runs=True, command=f"{_X}.sweep.command:sweep_cmd",
               other_commands=(f"{_X}.sweep.command:plot_sweep_cmd",)),
    Experiment("validate", spec=None, load=None, run=f"{_X}.validate.experiment:run_validate",
               result=f"{_X}.validate.experiment:ValidateResult",
               writer=f"{_X}.validate.experiment:write_validate_outputs", command=f"{_X}.validate.command:validate_cmd",
               other_commands=(f"{_X}.validate.command:cameras_cmd",)),
    Experiment("white-balance", spec=f"{_X}.white_balance.experiment:WhiteBalanceRun",
               load=f"{_X}.white_balance.experiment:plan", run=f"{_X}.white_balance.experiment:run_white_balance",
               result=f"{_X}.white_balance.experiment:WhiteBalanceResult",
               writer=f"{_X}.white_balance.experiment:write_white_balance_outputs",
               command=f"{_X}.white_balance.command:white_balance_cmd"),
    Experiment("spatial", spec=f"{_X}.spatial.experiment:SpatialSpec", load=f"{_X}.spatial.experiment:load_spatial",
               run=f"{_X}.spatial.experiment:run_spatial", result=f"{_X}.spatial.experiment:SpatialResult",
               writer=f"{_X}.spatial.report:write_outputs", command=f"{_X}.spatial.command:spatial_cmd"),
    Experiment("motion", spec=f"{_X}.motion.experiment:MotionSpec", load=f"{_X}.motion.experiment:load_motion",
               run=f"{_X}.motion.experiment:run_motion", result=f"{_X}.motion.experiment:MotionResult",
               writer=f"{_X}.motion.report:write_outputs", command=f"{_X}.motion.command:motion_cmd"),
    Experiment("dynamic-range", spec=f"{_X}.dynamic_range.experiment:DynamicRangeRun",
               load=f"{_X}.dynamic_range.experiment:plan", run=f"{_X}.dynamic_range.experiment:run_dynamic_range",
               result=f"{_X}.dynamic_range.experiment:DynamicRangeResult",
               writer=f"{_X}.dynamic_range.experiment:write_dynamic_range_outputs",
               command=f"{_X}.dynamic_range.command:dynamic_range_cmd"),
    Experiment("field", spec=f"{_X}.field.experiment:FieldRun", load=f"{_X}.field.experiment:plan",
               run=f"{_X}.field.experiment:run_field", result=f"{_X}.field.experiment:FieldResult",
               writer=f"{_X}.field.experiment:write_field_outputs", command=f"{_X}.field.command:field_cmd"),
    Experiment("datasheet", spec=f"{_X}.datasheet.experiment:DatasheetSpec", load=None,
               run=f"{_X}.datasheet.experiment:run_datasheet", result=f"{_X}.datasheet.experiment:DatasheetResult",
               writer=f"{_X}.datasheet.report:write_datasheet_outputs", command=f"{_X}.datasheet.command:datasheet_cmd"),
):
    EXPERIMENTS.register(_e.name, _e)
del _e
