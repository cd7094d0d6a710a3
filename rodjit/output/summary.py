"""What a run file says about its run, in a few numbers: the end-of-run report and ``info``.

``summarize`` reads it back from any file (diagnostics in blocks), also one being written
or one someone else wrote; ``closed_summary`` builds the same summary, number for number,
from what a writer kept while writing the file it just closed, without reading it back.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..config import Config
from ..records.extremes import Extremes
from ..records.overview import RunFacts, energy_label
from ..records.impact import run_impact
from ..records.stats import node_steps_per_second
from ..stepping import layout as L
from ..stepping.observers import params_of, values_of
from .h5files import open_file, writer_alive
from .run_layout import OBSERVED, SUMMARY_ATTRS, TABLES
from .run_reader import check_run_file, read_checkpoint, read_config, read_observed, read_table
from .run_writer import RunWriter

__all__ = ["RunSummary", "summarize", "closed_summary"]


@dataclass
class RunSummary:
    """The state and headline numbers of a run file (``rodjit info``, end of ``rodjit run``)."""

    path: str
    status: str
    message: str
    config: Config
    t: float
    t_end: float
    counts: dict
    bounces: dict
    energy0: float
    energy_error: float       # max |E + dissipated - E0| / max(|E0|, max kinetic energy);
                              # nan without diagnostics
    min_strain: float         # nan if nothing was sampled
    min_u0: float             # lowest bottom height seen (diagnostics and bounce records)
    max_floor_force: float    # largest floor force seen (nan if nothing was sampled)
    steps: int
    rejected_steps: int
    compile_time: float
    run_time: float
    node_steps_per_second: float
    attrs: dict = field(default_factory=dict)
    impact: dict = field(default_factory=dict)   # the first macroscopic contact
                                                 # (records.impact.IMPACT_COLUMNS)
    writer_alive: bool | None = None
    observed: dict = field(default_factory=dict)   # the observer's values
                                                   # (``Result.observed``)

    @property
    def warnings(self) -> tuple[str, ...]:
        """What the run's results cannot be trusted for (``Config.warnings``)."""
        return self.config.warnings()

    @property
    def n_bounces(self) -> int:
        return int(self.bounces["t_impact"].size)

    def energy_label(self) -> str:
        return energy_label(self.config.rod.mu)

    def facts(self) -> RunFacts:
        """What ``repr``, ``_repr_html_`` and ``report`` print (``records.overview``)."""
        return RunFacts(
            name=self.path, status=self.status, message=self.message, config=self.config,
            t_start=0.0,
            t=self.t, t_end=self.t_end, bounces=self.bounces,
            n_episodes=self.counts["episodes"], energy_error=self.energy_error,
            min_strain=self.min_strain, min_u0=self.min_u0, steps=self.steps,
            rejected=self.rejected_steps, compile_time=self.compile_time,
            run_time=self.run_time, node_steps_per_second=self.node_steps_per_second,
            warnings=self.warnings, impact=self.impact, observed=self.observed)

    def report(self, max_bounces: int | None = 20) -> str:
        """A short plain-text report: bounces (at most ``max_bounces`` rows, None: all),
        energy, extremes, steps and timings."""
        return self.facts().report(max_bounces)

    def __repr__(self) -> str:
        return self.facts().text()

    def _repr_html_(self) -> str:
        return self.facts().html()


def summarize(path) -> RunSummary:
    """Read the summary of the run file at ``path`` (also while it is being written)."""
    with open_file(path) as f:
        check_run_file(f, path)
        counts = {name: min(f[name][c].shape[0] for c in cols if c in f[name])
                  for name, cols in TABLES.items()}      # older formats lack some columns
        extremes = Extremes()
        extremes.read(f["diagnostics"], counts["diagnostics"])
        config, ck, bounces = read_config(f), read_checkpoint(f), read_table(f, "bounces")
        n_ep = counts["episodes"]
        impact = run_impact(config, float(ck["clock"][L.T]), ck["state"][0],
                            f["diagnostics"], counts["diagnostics"],
                            {c: f["episodes"][c][:n_ep] for c in ("t_start", "t_end")},
                            bounces)
        status = str(f.attrs["status"])
        return _summary(
            path, status, str(f.attrs["message"]), config, ck, counts, bounces, extremes,
            impact, {k: f.attrs[k] for k in SUMMARY_ATTRS if k in f.attrs},
            writer_alive(f) if status == "running" else None, read_observed(f, ck))


def closed_summary(writer: RunWriter) -> RunSummary:
    """The summary of the file ``writer`` has just closed, from what it wrote: equal to
    ``summarize(writer.path)``."""
    fin = writer.final
    if fin is None:
        raise ValueError(f"{writer.path!r} is not closed yet: no summary to take")
    ck = writer.checkpoint
    impact = writer.impact.values(float(ck["clock"][L.T]), ck["state"][0], writer.pending)
    observed = (values_of(params_of(writer.config), ck[OBSERVED]) if OBSERVED in ck
                else {})
    return _summary(writer.path, fin["status"], fin["message"], writer.config, ck,
                    fin["counts"], fin["bounces"], writer.extremes, impact, fin["attrs"],
                    None, observed)


def _summary(path, status, message, config, ck, counts, bounces, extremes: Extremes,
             impact: dict, attrs, alive, observed: dict) -> RunSummary:
    clock, count = ck["clock"], ck["count"]
    e0 = float(clock[L.E0])
    ext = extremes.with_bounces(bounces)
    steps = int(count[L.STEP])
    run_time = ck["run_time"]
    return RunSummary(
        path=str(path), status=status, message=message, config=config,
        t=float(clock[L.T]), t_end=float(config.time.t_end), counts=counts, bounces=bounces,
        energy0=e0, energy_error=ext.energy_error(e0),
        min_strain=ext.strain_min if math.isfinite(ext.strain_min) else math.nan,
        min_u0=ext.u0_min if math.isfinite(ext.u0_min) else math.inf,
        max_floor_force=ext.force_max if math.isfinite(ext.force_max) else math.nan,
        steps=steps, rejected_steps=int(count[L.REJECTED]),
        compile_time=ck["compile_time"], run_time=run_time,
        node_steps_per_second=node_steps_per_second(steps, config.rod.N + 1, run_time),
        attrs=attrs, writer_alive=alive,
        impact=impact, observed=observed,
    )
