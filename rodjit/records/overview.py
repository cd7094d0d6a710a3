"""A run told in a few lines, the same for a ``Result`` (in memory) and a ``RunSummary``
(a file): the rows of their ``repr``/``_repr_html_`` and the plain-text ``report``."""
from __future__ import annotations

import math

import numpy as np

from .._display import html_table, number, text
from .impact import impact_line

__all__ = ["RunFacts", "energy_label"]

SHOWN_RESTITUTIONS = 4      # restitutions listed in the overview (the rest: "...")


def energy_label(mu: float) -> str:
    return "energy drift" if mu == 0 else "energy balance error"


class RunFacts:
    """What the overview and the report of a run print.  ``min_u0`` is +inf without
    contact; ``energy_error``/``min_strain`` NaN when nothing was sampled."""

    def __init__(self, *, name, status, message, config, t_start, t, t_end, bounces,
                 n_episodes, energy_error, min_strain, min_u0, steps, rejected,
                 compile_time, run_time, node_steps_per_second, warnings=(), impact=None,
                 observed=None):
        self.name, self.status, self.message, self.config = name, status, message, config
        self.warnings = tuple(warnings)   # what the results do not mean (Config.warnings)
        self.impact = impact or {}        # the first macroscopic contact (records.impact)
        self.observed = observed or {}    # the observer's values (``output.observer``)
        self.t_start, self.t, self.t_end = t_start, t, t_end
        self.bounces, self.n_episodes = bounces, n_episodes
        self.energy_error, self.min_strain, self.min_u0 = energy_error, min_strain, min_u0
        self.steps, self.rejected = steps, rejected
        self.compile_time, self.run_time = compile_time, run_time
        self.node_steps_per_second = node_steps_per_second

    # ---- the short overview (repr) ------------------------------------------------------
    def title(self) -> str:
        c = self.config
        # "(auto)": ``report`` and ``config.choice`` give the row of the table that chose it
        return (f"{self.name}: {self.status}, N = {c.rod.N}, mu = {c.rod.mu:g}, "
                f"{c.time.integrator}" + (" (auto)" if c.choice else ""))

    def rows(self) -> list[tuple[str, str]]:
        b = self.bounces
        n = int(b["t_impact"].size)
        e = [(self._open(i) if b["open"][i] else number(b["restitution"][i], ".4f")
              + ("?" if b["ambiguous"][i] else ""))
             for i in range(min(n, SHOWN_RESTITUTIONS))]
        bounces = f"{n}" + (f" (restitution {', '.join(e)}{', ...' if n > len(e) else ''})"
                            if n else "")
        rows = [("time", f"{self.t_start:.6g} to {self.t:.6g} of {self.t_end:.6g} s"),
                ("bounces", bounces),
                (energy_label(self.config.rod.mu), number(self.energy_error, ".3g")),
                ("steps", f"{self.steps} ({self.rejected} rejected)"),
                ("wall time", f"{self.compile_time + self.run_time:.3g} s "
                              f"({self.compile_time:.3g} s compiling)")]
        if self.stop_reason():
            rows.insert(0, ("stopped", self.stop_reason()))
        if self.message:
            rows.insert(0, ("message", self.message))
        rows.extend(("warning", w) for w in self.warnings)
        return rows

    def stop_reason(self) -> str:
        """Why a completed run ended before ``time.t_end`` ('' where it did not): its
        bounces were over (``time.stop_after_bounces``) or it came to rest
        (``time.stop_at_rest``)."""
        c = self.config
        if self.status != "completed" or not self.t < self.t_end - 1e-9 * abs(self.t_end):
            return ""
        k = int(c.time.stop_after_bounces)
        over = int(np.count_nonzero(~np.asarray(self.bounces["open"], bool)))
        if k and over >= k:
            return (f"ended after {k} bounce{'s' if k != 1 else ''} "
                    f"(time.stop_after_bounces = {k})")
        if c.time.stop_at_rest:
            return ("ended at rest: the energy fell below the lift-off energy, so the rod "
                    "never leaves the floor again (time.stop_at_rest)")
        return ""

    def _open(self, i: int) -> str:
        """What the restitution of the open bounce ``i`` (in contact at the end) reads: "no
        lift-off" where that bounce is the first impact and its energy is below the
        lift-off energy (it can never end: ``impact_status``, restitution_first 0), else
        "open" (it may still end)."""
        b = self.bounces
        no_lift = (bool(self.impact) and self.impact.get("impact_status") == "no lift-off"
                   and i == int(b["t_impact"].size) - 1)
        return "no lift-off" if no_lift else "open"

    def text(self) -> str:
        return text(self.title(), self.rows())

    def html(self) -> str:
        return html_table(self.title(), self.rows())

    # ---- the report ---------------------------------------------------------------------
    def report(self, max_bounces: int | None = 20) -> str:
        """Bounces (at most ``max_bounces`` rows, None: all), energy, extremes, steps and
        timings, as plain text."""
        c = self.config
        lines = [f"{self.name}: {self.status} at t = {self.t:.6g} of {self.t_end:.6g} "
                 f"(N = {c.rod.N}, mu = {c.rod.mu:g}, {c.time.integrator})"]
        if c.choice:
            lines.append(f"  integrator {c.ran_with()}")
        if self.stop_reason():
            lines.append(f"  {self.stop_reason()}")
        if self.message:
            lines.append(f"  {self.message}")
        lines.extend(f"  warning: {w}" for w in self.warnings)
        b = self.bounces
        n = int(b["t_impact"].size)
        lines.append(f"  {n} bounce{'s' if n != 1 else ''}, "
                     f"{self.n_episodes} finished contact episodes")
        if n:
            lines.append("      #   t_impact  t_release  episodes   w_impact  w_release  "
                         "restitution  e_energy")
            show = list(range(n))
            if max_bounces is not None and n > max_bounces:
                half = max_bounces // 2
                show = show[:half] + [-1] + show[n - half:]
            for i in show:
                if i < 0:
                    lines.append("    ...")
                    continue
                e = self._open(i) if b["open"][i] else _num(b["restitution"][i], ".4f")
                lines.append(f"  {i + 1:5d} {_num(b['t_impact'][i], '10.4f')} "
                             f"{_num(b['t_release'][i], '10.4f')} {int(b['n_episodes'][i]):9d} "
                             f"{_num(b['w_impact'][i], '10.4f')} {_num(b['w_release'][i], '10.4f')}"
                             f"  {e:>11} {_num(b['restitution_energy'][i], '9.4f')}"
                             f"{' ?' if b['ambiguous'][i] else ''}")
            if np.asarray(b["ambiguous"], bool).any():
                lines.append("      ?: ambiguous, not an impact's restitution (not over at the "
                             "end, or the approach below 0.2 of the vibration speed)")
        if self.impact:
            lines.append(f"  {'first impact':<22}{impact_line(self.impact)}")
        if self.observed:
            lines.append(f"  {'observer ' + c.output.observer:<22}"
                         + ", ".join(f"{k} = {v:.9g}" for k, v in self.observed.items()))
        label = energy_label(c.rod.mu)
        if math.isnan(self.energy_error):
            lines.append(f"  {label:<22}not measured (no diagnostics: "
                         f"output.diagnostics_interval = 0)")
        else:
            lines.append(f"  {label:<22}{self.energy_error:.3g}  "
                         f"(max |E + dissipated - E0| / max(|E0|, kinetic))")
        lines.append(f"  {'smallest strain':<22}{_num(self.min_strain, '.6g')}")
        if self.min_u0 < 0:
            lines.append(f"  {'deepest penetration':<22}{-self.min_u0:.6g}  "
                         f"(u_0 = {self.min_u0:.6g}; floor limit -beta = {-c.floor.beta:g})")
        else:
            lines.append(f"  {'deepest penetration':<22}none (no contact)")
        lines.append(f"  {'steps':<22}{self.steps} ({self.rejected} rejected)")
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
