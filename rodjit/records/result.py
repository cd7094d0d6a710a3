"""The in-memory result of a run (what ``simulate`` returns and ``load_file`` reads) and
the sink that collects it."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._extras import need
from .bounces import bounce_table
from .columns import DIAG_COLUMNS, EPISODE_COLUMNS, columns_of
from .datasets import run_dataset, strain_of
from .extremes import Extremes
from .impact import run_impact
from .overview import RunFacts
from .sink import Sink

if TYPE_CHECKING:
    from ..config import Config

__all__ = ["Result", "MemorySink"]


@dataclass(repr=False)
class Result:
    """Everything a run produced: what ``simulate`` returns and ``load_file`` reads.

    Attributes
    ----------
    config : Config
        The resolved configuration of the run.
    x : numpy.ndarray
        Reference positions of the N + 1 nodes [m], shape ``(N + 1,)``.
    t : numpy.ndarray
        Snapshot times [s], shape ``(n_snapshots,)``.
    u : numpy.ndarray
        Node heights at the snapshots [m], shape ``(n_snapshots, N + 1)``.
    v : numpy.ndarray
        Node velocities at the snapshots [m s⁻¹], same shape as ``u``.
    diagnostics : dict
        Column name -> array, the columns of ``records.columns.DIAG_COLUMNS`` (``t``,
        ``dt``, energies, ``dissipated``, the floor and strain extremes, the centre of
        mass), one row per diagnostics sample.
    episodes : dict
        ``t_start``, ``t_end`` arrays: the intervals with the bottom in contact.
    bounces : dict
        ``records.bounces.bounce_table``: the MODEL.md §3 columns (``restitution``,
        ``restitution_energy``, ``ambiguous``, ...) plus ``open``, one entry per bounce, a
        physical impact.
    stats : dict
        Steps, rejected steps, wall/compile/run time, node-steps per second.
    status : str
        ``"completed"``, or the state the run stopped in (``"failed"``; a file read by
        ``load_file`` keeps the status it records).
    message : str
        The reason for a status other than ``"completed"``.
    t_final : float
        Simulated time reached [s].
    u_final, v_final : numpy.ndarray
        Heights and velocities at ``t_final``, shape ``(N + 1,)``.
    energy0 : float
        Total energy at t = 0 [J].
    dissipated : float
        Energy dissipated by the viscosity up to ``t_final`` [J].
    observed : dict
        Column name -> value of the run's observer (``output.observer``,
        ``rodjit.observers``) at ``t_final``; empty without one.
    """

    config: Config
    x: np.ndarray
    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    diagnostics: dict
    episodes: dict
    bounces: dict
    stats: dict
    status: str = "completed"
    message: str = ""
    t_final: float = 0.0
    u_final: np.ndarray = field(default_factory=lambda: np.zeros(0))
    v_final: np.ndarray = field(default_factory=lambda: np.zeros(0))
    energy0: float = 0.0
    dissipated: float = 0.0
    observed: dict = field(default_factory=dict)

    @property
    def n_bounces(self) -> int:
        """Number of rows of ``bounces`` (an open last bounce included)."""
        return int(self.bounces["t_impact"].size)

    def energy_error(self) -> float:
        """max |E(t) + dissipated(t) − E(0)| / scale over the diagnostics samples, scale =
        max(|E(0)|, max kinetic energy): the drift at μ = 0, the balance error at μ > 0
        (NaN without diagnostics samples)."""
        ext = Extremes()
        ext.update(*(self.diagnostics[c] for c in Extremes.COLUMNS))
        return ext.energy_error(self.energy0)

    # ---- showing it ---------------------------------------------------------------------
    def facts(self) -> RunFacts:
        """What ``repr``, ``_repr_html_`` and ``report`` print (``records.overview``)."""
        ext = Extremes()
        ext.update(*(self.diagnostics[c] for c in Extremes.COLUMNS))
        ext = ext.with_bounces(self.bounces)
        s = self.stats
        return RunFacts(
            name="rodjit.Result", status=self.status, message=self.message,
            config=self.config, t_start=float(self.t[0]) if self.t.size else 0.0,
            t=self.t_final, t_end=self.config.time.t_end, bounces=self.bounces,
            n_episodes=int(self.episodes["t_start"].size),
            energy_error=ext.energy_error(self.energy0),
            min_strain=ext.strain_min if np.isfinite(ext.strain_min) else np.nan,
            min_u0=ext.u0_min, steps=int(s.get("steps", 0)),
            rejected=int(s.get("rejected_steps", 0)),
            compile_time=float(s.get("compile_time", 0.0)),
            run_time=float(s.get("run_time", 0.0)),
            node_steps_per_second=float(s.get("node_steps_per_second", 0.0)),
            warnings=self.config.warnings(), impact=self.impact(), observed=self.observed)

    def impact(self) -> dict:
        """The first macroscopic contact (``records.impact.IMPACT_COLUMNS``), as a run
        file's summary and a sweep row report it."""
        return run_impact(self.config, self.t_final, self.u_final, self.diagnostics,
                          int(self.diagnostics["t"].size), self.episodes, self.bounces)

    def report(self, max_bounces: int | None = 20) -> str:
        """The plain-text report ``rodjit run`` prints: bounces (at most ``max_bounces``
        rows, None: all), energy, extremes, steps and timings.

        Parameters
        ----------
        max_bounces : int or None
            Most bounce rows shown (the first ones); None shows every bounce.

        Returns
        -------
        str
            The report, several lines.
        """
        return self.facts().report(max_bounces)

    def __repr__(self) -> str:
        return self.facts().text()

    def _repr_html_(self) -> str:
        return self.facts().html()

    # ---- converting it ------------------------------------------------------------------
    def to_xarray(self) -> Any:
        """An ``xarray.Dataset``: ``u``, ``v`` on (``t``, ``x``), ``strain`` on (``t``,
        ``x_segment``), the diagnostics on ``t_diag``, episodes along ``episode``, bounces
        along ``bounce`` (``records.datasets``); every variable with units and long_name."""
        return run_dataset(
            x=self.x, t=self.t, u=self.u, v=self.v, strain=strain_of(self.u, self.x.size - 1),
            diagnostics=self.diagnostics, episodes=self.episodes, bounces=self.bounces,
            attrs={"status": self.status, "config_toml": self.config.to_toml()},
            what="Result.to_xarray")

    def to_pandas(self) -> dict:
        """``{"diagnostics": DataFrame indexed by t, "bounces": DataFrame indexed by bounce
        number (from 1), "episodes": DataFrame}``."""
        pd = need("pandas", "analysis", "Result.to_pandas")
        diag = pd.DataFrame(self.diagnostics).set_index("t")
        bounces = pd.DataFrame(self.bounces,
                               index=pd.RangeIndex(1, self.n_bounces + 1, name="bounce"))
        episodes = pd.DataFrame(self.episodes)
        episodes.index.name = "episode"
        return {"diagnostics": diag, "bounces": bounces, "episodes": episodes}


def _joined(parts, empty_shape):
    """The blocks a sink copied, as one array: the block itself when there is one (it is
    the sink's own copy already), else their concatenation."""
    if not parts:
        return np.zeros(empty_shape)
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


class MemorySink(Sink):
    """Collects drained blocks in lists; ``result`` concatenates them once at the end.

    With ``views=True`` the sink keeps the views it is given, uncopied, until ``settle``
    copies them: its owner calls ``settle`` before the run refills its buffers (before each
    compiled call after the first drain), so a run whose rows all come in one block (every
    run whose buffers hold its output: ``driver.run.capacities``) is never copied
    here, and the Result takes its columns from the buffers with one copy or none
    (``simulate``, which owns the run and drops it after)."""

    def __init__(self, views: bool = False) -> None:
        self._t: list[np.ndarray] = []
        self._step: list[np.ndarray] = []
        self._u: list[np.ndarray] = []
        self._v: list[np.ndarray] = []
        self._diag: list[np.ndarray] = []
        self._ep: list[np.ndarray] = []
        self._b: list[np.ndarray] = []
        self._views = views
        self._unsettled: list[tuple[list, int]] = []   # (list, index) of kept views

    def _keep(self, parts: list, rows) -> None:
        if self._views:
            self._unsettled.append((parts, len(parts)))
            parts.append(rows)
        else:
            parts.append(rows.copy())

    def settle(self) -> None:
        """Copy the views kept since the last call (``views=True``): the run's buffers may
        be refilled after this."""
        for parts, i in self._unsettled:
            parts[i] = parts[i].copy()
        self._unsettled.clear()

    def snapshots(self, t, step, u, v):
        self._keep(self._t, t)
        self._keep(self._step, step)
        self._keep(self._u, u)
        self._keep(self._v, v)

    def diagnostics(self, rows):
        self._keep(self._diag, rows)

    def episodes(self, rows):
        self._keep(self._ep, rows)

    def bounces(self, rows):
        self._keep(self._b, rows)

    def result(self, run, status="completed", message="") -> Result:
        n1 = run.system.n + 1
        diag = _joined(self._diag, (0, len(DIAG_COLUMNS)))
        ep = _joined(self._ep, (0, len(EPISODE_COLUMNS)))
        return Result(
            config=run.config,
            x=run.x.copy(),
            t=_joined(self._t, (0,)),
            u=_joined(self._u, (0, n1)),
            v=_joined(self._v, (0, n1)),
            diagnostics=columns_of(diag, DIAG_COLUMNS),
            episodes=columns_of(ep, EPISODE_COLUMNS),
            bounces=bounce_table(self._b, run.pending_bounce()),
            stats=run.stats(),
            status=status,
            message=message,
            t_final=run.t,
            u_final=run.u.copy(),
            v_final=run.v.copy(),
            energy0=run.energy0,
            dissipated=run.dissipated,
            observed=run.observed,
        )
