"""What ``rodjit info`` says about a rodjit file, for every kind of file (runs, sweeps,
convergence studies).

One path for every kind: ``info`` reads the file's kind, asks that kind's reader for an
``About`` (format version, attributes, status, the kind's own lines, configuration and
report), and lays it out the same way: header, details, configuration, report.  Adding a
file kind is one reader and one ``READERS`` entry.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .output.h5files import NotARunFile, damaged, file_kind, writer_alive
from .output.lock import failure_note
from .output.run_layout import FORMAT_VERSION as RUN_FORMAT_VERSION
from .output.summary import summarize
from .sweeps import sweep_file
from .sweeps.grid import format_value
from .sweeps.sweep_table import load_sweep

__all__ = ["About", "READERS", "readable_kind", "about", "info"]


@dataclass
class About:
    """What ``info`` prints of one file, below the header line ``rodjit KIND file PATH``."""

    version: int              # the file's format version
    attrs: dict               # root attributes (rodjit_version, created, command, ...)
    status: str               # the status line, with what it means for a running file
    details: list[str] = field(default_factory=list)   # the kind's own lines
    config_title: str = "configuration:"
    config: Any = None        # the rodjit.Config shown as TOML
    report: str = ""          # the kind's table (bounces of a run, points of a sweep)


def _about_run(path: str) -> About:
    s = summarize(path)
    status = s.status
    if status == "running":
        if s.writer_alive:
            status += " (the writing process is alive)"
        elif s.writer_alive is False and failure_note(path):
            status = (f"failed ({failure_note(path)}; 'rodjit run --resume {path}' continues "
                      f"from the checkpoint at t = {s.t:.6g} once there is space)")
        elif s.writer_alive is False:
            status += (f" (the writing process is gone: it was killed; 'rodjit run --resume "
                       f"{path}' continues from the checkpoint at t = {s.t:.6g})")
    c = s.counts
    return About(int(s.attrs.get("format_version", RUN_FORMAT_VERSION)), s.attrs, status,
                 [f"rows      {c['snapshots']} snapshots, {c['diagnostics']} diagnostics, "
                  f"{c['episodes']} episodes, {c['bounces']} bounces"],
                 "configuration:", s.config, s.report(max_bounces=None))


def _about_sweep(path: str) -> About:
    table = load_sweep(path)
    a = table.attrs
    status = table.status
    if status == "running":
        with sweep_file.open_sweep(path) as f:
            alive = writer_alive(f)
        if alive is False and failure_note(path):
            status = (f"failed ({failure_note(path)}; 'rodjit sweep --resume -o {path}' "
                      f"runs the points not written once there is space)")
        else:
            status += (" (the sweep is running)" if alive else
                       f" (its process is gone; 'rodjit sweep --resume -o {path}' continues)"
                       if alive is False else "")
    c = table.counts
    details = [f"points    {len(table)} ({c['completed']} completed, {c['failed']} failed, "
               f"{c['pending']} not run) on {a.get('scheduler', '?')}", "grid:"]
    details += [f"  {key} = {', '.join(format_value(v) for v in values)}"
                for key, values in zip(table.grid.keys, table.grid.values)]
    if a.get("save_runs"):
        details.append(f"run files {a['save_runs']}")
    if table.base.choice:        # the integrator "auto" chose for every point
        details.append(f"integrator {table.base.ran_with()}")
    return About(int(a.get("format_version", sweep_file.FORMAT_VERSION)), a,
                 status + (f": {table.message}" if table.message else ""), details,
                 "base configuration:", table.base, table.report())


def _about_convergence(path: str) -> About:
    import math

    from .analysis.converge import FORMAT_VERSION as CONVERGENCE_FORMAT_VERSION
    from .analysis.converge import load_convergence
    from .config import Config

    d = load_convergence(path)

    def listed(values) -> str:       # the ladders are stored as floats
        return ", ".join(f"{float(v):g}" for v in values)

    details = [f"ladder    {d['key']} = {listed(d['levels'])}"]
    if d.get("time_key"):
        details.append(f"time      {d['time_key']} = {listed(d['time_levels'])} at "
                       f"{d['key']} = {float(d['time_at']):g}")
        p = float(d.get("predictability_time", math.nan))
        details.append("predictability time " + (
            "not measured" if math.isnan(p) else "none before t_end" if p == math.inf
            else f"{p:.4g} s"))
    rows = ["observables (continuum value ± error, observed order, status):"]
    for name, o in d["observables"].items():
        order = float(o.get("order", math.nan))
        rows.append(f"  {name}: {float(o['value']):.6g} ± {float(o['error']):.2g}  "
                    f"p={f'{order:.2f}' if math.isfinite(order) else '—'}  {o['status']}")
    rows += [f"  warning: {w}" for w in str(d.get("warnings", "")).splitlines() if w]
    return About(int(d.get("format_version", CONVERGENCE_FORMAT_VERSION)), d, "completed",
                 details, "base configuration:", Config.from_stored_toml(str(d["config"])),
                 "\n".join(rows))


# rodjit_kind -> About of a file
READERS = {"run": _about_run, "sweep": _about_sweep, "convergence": _about_convergence}


def readable_kind(path) -> str:
    """The kind of the rodjit file at ``path``; NotARunFile (a ValueError, one line) if it
    is not a rodjit file or one of a kind this version cannot read."""
    kind = file_kind(path)
    if kind not in READERS:
        raise NotARunFile(f"{str(path)!r} is a rodjit {kind!r} file, which this version of "
                          f"rodjit cannot read")
    return kind


def about(path) -> tuple[str, About]:
    """The kind of the file at ``path`` and what ``info`` prints of it."""
    kind = readable_kind(path)
    with damaged(path):
        return kind, READERS[kind](str(path))


def info(path) -> str:
    """The text of ``rodjit info PATH``: what the file is, who wrote it, its status, the
    kind's details, the configuration and the report.  ValueError (one line) for a file
    that is missing, not a rodjit file or of an unknown kind."""
    kind, a = about(path)
    attrs = a.attrs
    lines = [f"rodjit {kind} file {path} (format {a.version}, written by rodjit "
             f"{attrs.get('rodjit_version', '?')})",
             f"created   {attrs.get('created', '?')}",
             f"command   {attrs.get('command', '?')}",
             f"status    {a.status}"]
    lines += a.details
    lines.append(a.config_title)
    lines += [f"  {line}" for line in a.config.to_toml().strip().splitlines()]
    lines.append(a.report)
    return "\n".join(lines)
