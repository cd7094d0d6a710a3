"""What a run file says about its run, in a few numbers: the end-of-run report and ``info``.

``summarize`` reads it back from any file (diagnostics in blocks), also one being written
or one someone else wrote; ``closed_summary`` builds the same summary, number for number,
from what a writer kept while writing the file it just closed, without reading it back.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..records.extremes import Extremes
from ..records.observables import ImpactTrack, impact_line, impact_values
from ..records.stats import node_steps_per_second
from ..stepping import layout as L
from .h5files import open_file, writer_alive
from .run_layout import SUMMARY_ATTRS, TABLES
from .run_reader import check_run_file, read_checkpoint, read_config, read_table
from .run_writer import RunWriter

__all__ = ["RunSummary", "summarize", "closed_summary"]


@dataclass
class RunSummary:
    """The state and headline numbers of a run file (``rodjit info``, end of ``rodjit run``)."""

    path: str
    status: str
    message: str
    config: object
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
                                                 # (records.observables.IMPACT_COLUMNS)
    writer_alive: bool | None = None

    @property
    def n_bounces(self) -> int:
        return int(self.bounces["t_impact"].size)

    def energy_label(self) -> str:
        return "energy drift" if self.config.rod.mu == 0 else "energy balance error"

    def report(self, max_bounces: int | None = 20) -> str:
        """A short plain-text report: bounces (at most ``max_bounces`` rows, None: all),
        energy, extremes, steps and timings."""
        c = self.config
        lines = [f"{self.path}: {self.status} at t = {self.t:.6g} of {self.t_end:.6g} "
                 f"(N = {c.rod.N}, mu = {c.rod.mu:g}, {c.time.integrator})"]
        if self.message:
            lines.append(f"  {self.message}")
        b = self.bounces
        n = self.n_bounces
        lines.append(f"  {n} bounce{'s' if n != 1 else ''}, "
                     f"{self.counts['episodes']} finished contact episodes")
        if n:
            lines.append("      #   t_impact  t_release  episodes   w_impact  w_release  "
                         "restitution")
            show = list(range(n))
            if max_bounces is not None and n > max_bounces:
                half = max_bounces // 2
                show = show[:half] + [-1] + show[n - half:]
            for i in show:
                if i < 0:
                    lines.append("    ...")
                    continue
                e = "open" if b["open"][i] else _num(b["restitution"][i], ".4f")
                lines.append(f"  {i + 1:5d} {_num(b['t_impact'][i], '10.4f')} "
                             f"{_num(b['t_release'][i], '10.4f')} {int(b['n_episodes'][i]):9d} "
                             f"{_num(b['w_impact'][i], '10.4f')} {_num(b['w_release'][i], '10.4f')}"
                             f"  {e:>11}")
        if self.impact:
            lines.append(f"  {'first impact':<22}{impact_line(self.impact)}")
        if math.isnan(self.energy_error):
            lines.append(f"  {self.energy_label():<22}not measured (no diagnostics: "
                         f"output.diagnostics_interval = 0)")
        else:
            lines.append(f"  {self.energy_label():<22}{self.energy_error:.3g}  "
                         f"(max |E + dissipated - E0| / max(|E0|, kinetic))")
        lines.append(f"  {'smallest strain':<22}{_num(self.min_strain, '.6g')}")
        if self.min_u0 < 0:
            lines.append(f"  {'deepest penetration':<22}{-self.min_u0:.6g}  "
                         f"(u_0 = {self.min_u0:.6g}; floor limit -beta = {-c.floor.beta:g})")
        else:
            lines.append(f"  {'deepest penetration':<22}none (no contact)")
        lines.append(f"  {'steps':<22}{self.steps} ({self.rejected_steps} rejected)")
        lines.append(f"  {'compile time':<22}{self.compile_time:.3g} s")
        lines.append(f"  {'run time':<22}{self.run_time:.3g} s "
                     f"({self.node_steps_per_second:.3g} node-steps/s)")
        return "\n".join(lines)


def _num(value, spec: str) -> str:
    """Format a number; NaN (no value, e.g. the release of an open bounce) prints as '-'."""
    value = float(value)
    if math.isnan(value):
        width = spec.split(".")[0]
        return "-".rjust(int(width) if width else 1)
    return format(value, spec)


def summarize(path) -> RunSummary:
    """Read the summary of the run file at ``path`` (also while it is being written)."""
    with open_file(path) as f:
        check_run_file(f, path)
        counts = {name: min(f[name][c].shape[0] for c in cols)
                  for name, cols in TABLES.items()}
        extremes = Extremes()
        extremes.read(f["diagnostics"], counts["diagnostics"])
        track = ImpactTrack()
        track.read(f, counts["diagnostics"], counts["episodes"])
        status = str(f.attrs["status"])
        return _summary(
            path, status, str(f.attrs["message"]), read_config(f), read_checkpoint(f),
            counts, read_table(f, "bounces"), extremes, track,
            {k: f.attrs[k] for k in SUMMARY_ATTRS if k in f.attrs},
            writer_alive(f) if status == "running" else None)


def closed_summary(writer: RunWriter) -> RunSummary:
    """The summary of the file ``writer`` has just closed, from what it wrote: equal to
    ``summarize(writer.path)``."""
    fin = writer.final
    return _summary(writer.path, fin["status"], fin["message"], writer.config,
                    writer.checkpoint, fin["counts"], fin["bounces"], writer.extremes,
                    writer.track, fin["attrs"], None)


def _summary(path, status, message, config, ck, counts, bounces, extremes: Extremes,
             track: ImpactTrack, attrs, alive) -> RunSummary:
    clock, count = ck["clock"], ck["count"]
    e0 = float(clock[L.E0])
    ext = extremes.with_bounces(bounces)
    steps = int(count[L.STEP])
    run_time = ck["run_time"]
    return RunSummary(
        path=str(path), status=status, message=message, config=config,
        t=float(clock[L.T]), t_end=float(clock[L.T_END]), counts=counts, bounces=bounces,
        energy0=e0, energy_error=ext.energy_error(e0),
        min_strain=ext.strain_min if math.isfinite(ext.strain_min) else math.nan,
        min_u0=ext.u0_min if math.isfinite(ext.u0_min) else math.inf,
        max_floor_force=ext.force_max if math.isfinite(ext.force_max) else math.nan,
        steps=steps, rejected_steps=int(count[L.REJECTED]),
        compile_time=ck["compile_time"], run_time=run_time,
        node_steps_per_second=node_steps_per_second(steps, config.rod.N + 1, run_time),
        attrs=attrs, writer_alive=alive,
        impact=impact_values(config, float(clock[L.T]), ck["state"][0], track, bounces),
    )
