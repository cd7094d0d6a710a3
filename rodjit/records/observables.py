"""Observables of a run that are always defined (docs/MODEL.md §3).

The compiled event tracking splits a run into contact *episodes* (``u_0 < 0``) and
*bounces*, one per physical impact: a bounce ends at a *flight*, a release after which the
bottom stays off the floor for at least τ = π h/c (``flight_time``, the period of the
highest mode of the semi-discrete rod) and the centre of mass turns over (it leaves rising and
comes back falling).  Here the same rule (``flight_groups``) groups a run's episodes into
*macroscopic contacts*, one per bounce, for any τ, and the first-impact observables are
read at their ends, with the centre-of-mass state carried to the contact's end points along
the exact free-flight parabola from the nearest diagnostics sample in flight.

Everything here is plain NumPy over a run's diagnostics, episode and bounce arrays; the
few numbers that come from the configuration (gravity, wave speed, the energy needed to
leave the floor) travel in a ``Physics`` tuple built by ``physics_of``.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import NamedTuple

import numpy as np

from .._jit import python_function

__all__ = ["Physics", "physics_of", "physics_for", "ImpactTrack", "impact_values", "flight_time",
           "IMPACT_COLUMNS", "impact_line", "wave_speed", "lift_energy", "energy_vibration",
           "merge_episodes", "flight_groups", "macroscopic_contacts", "FirstImpact", "first_impact",
           "observables", "OBSERVABLES", "STATUSES"]

# a contact still open at the end with E(t_end) below the lift-off energy can never end
STATUSES = ("lift-off", "no lift-off", "open", "no impact")

# name -> description of the scalar observables ``observables`` returns
OBSERVABLES: dict[str, str] = {
    "restitution_first": "-w_release/w_impact of the first bounce (the first physical "
                         "impact); 0 if the rod never leaves the floor",
    "restitution_apex_first": "sqrt of rebound over drop apex height of the centre of mass "
                              "above 1/2 (g < 0; kinetic-energy ratio at g = 0)",
    "contact_time_first": "t_release - t_impact of the first macroscopic contact (inf: no "
                          "lift-off)",
    "rebound_speed_first": "largest centre-of-mass velocity from the first impact to its "
                           "release (to the end of the run without lift-off)",
    "min_u0_first": "deepest penetration min u_0 during the first macroscopic contact",
    "max_floor_force_first": "largest floor force during the first macroscopic contact",
    "vibration_share_first": "energy_vibration / (energy_vibration + w^2/2) at release of "
                             "the first macroscopic contact",
    "min_u0": "lowest bottom height u_0 of the run",
    "max_floor_force": "largest floor force of the run",
}


class Physics(NamedTuple):
    """Numbers of the configuration the observables need (``physics_of``).

    Attributes
    ----------
    g : float
        Signed gravity along +u [m s⁻²].
    wave_speed : float
        c = sqrt(f'(0)) [m s⁻¹].
    lift_energy : float
        Least energy of a state with u_0 >= 0 [J] (−inf: no bound).
    t_final : float
        End of the run [s].
    flight_time : float
        τ [s]: a release followed by this long off the floor, with the centre of mass
        turning over, ends a macroscopic contact (a bounce).
    in_contact : bool
        u_0 < 0 at ``t_final``.
    contact_start : float
        Start of the episode still running at ``t_final`` [s] (NaN: none).
    """

    g: float              # signed gravity along +u
    wave_speed: float     # c = sqrt(f'(0))
    lift_energy: float    # least energy of a state with u_0 >= 0 (-inf: no bound)
    t_final: float        # end of the run
    flight_time: float    # τ: a flight is this long off the floor (and a turn-over)
    in_contact: bool      # u_0 < 0 at t_final
    contact_start: float  # start of the episode still running at t_final (NaN: none)


def wave_speed(config) -> float:
    """Elastic wave speed c = sqrt(f'(0)) of the rod law (sqrt(5κ/4) for Aiki–Kosugi).

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` section).

    Returns
    -------
    float
        c [m s⁻¹] in the reference length of the rod (length 1, mass 1).
    """
    from ..model.laws import get_law

    law = get_law("rod", config.rod.law)
    return math.sqrt(float(python_function(law.deriv)(0.0, law.from_config(config.rod))))


def flight_time(config) -> float:
    """τ = π h/c, the period of the highest mode of the semi-discrete rod (ω_max = 2c/h,
    c the ``wave_speed``, h = 1/N): the shortest time the discretisation resolves.  A
    release ends a bounce only if the bottom then stays off the floor at least this long
    and the centre of mass turns over (MODEL.md §3).

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` section).

    Returns
    -------
    float
        τ [s].
    """
    return math.pi / (config.rod.N * wave_speed(config))


def lift_energy(config) -> float:
    """min V(u) over the states with u_0 >= 0 (no kinetic energy), for g < 0: the rod
    standing on the floor at u_0 = 0 under its weight, each segment compressed by the
    weight above it, f(ε_{j+½}) = g Σ_{i>j} m_i.  The energy never increases, so a run
    whose energy falls below this can never have its bottom leave the floor again.
    ``-inf`` for g > 0 (no such bound), 0 for g = 0.

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` and ``gravity`` sections).

    Returns
    -------
    float
        The energy [J].
    """
    from ..model.laws import get_law, lower
    from ..model.system import masses

    g = float(config.gravity.g)
    if g > 0:
        return -math.inf
    if g == 0:
        return 0.0
    law = get_law("rod", config.rod.law)
    p = law.from_config(config.rod)
    value, primitive = python_function(law.value), python_function(law.primitive)
    n = config.rod.N
    m = masses(n)
    load = g * (1.0 - np.cumsum(m))[:-1]        # g · (mass above segment j), j = 0..N-1
    lo = float(lower(p))
    eps = np.empty(n)
    for j, s in enumerate(load):
        a, b = lo, 0.0                          # f(a) < s <= f(0) = 0: bisection to rounding
        if s == 0.0:
            eps[j] = 0.0
            continue
        for _ in range(200):
            mid = 0.5 * (a + b)
            if mid in (a, b):
                break
            if value(mid, p) < s:
                a = mid
            else:
                b = mid
        eps[j] = 0.5 * (a + b)
    h = 1.0 / n
    u = np.concatenate([[0.0], np.cumsum(h * (1.0 + eps))])
    stretch = sum(h * float(primitive(e, p)) for e in eps)
    return stretch - g * float(m @ u)


def physics_of(result, merge_time: float | None = None) -> Physics:
    """The Physics of a Result.

    Parameters
    ----------
    result : Result
        A run, from ``simulate`` or ``load_file``.
    merge_time : float, optional
        The flight time τ [s] that ends a macroscopic contact (``flight_groups``);
        default ``flight_time(config)`` = π h/c, the one the bounce table uses.

    Returns
    -------
    Physics

    Raises
    ------
    ValueError
        ``merge_time`` <= 0.
    """
    return physics_for(result.config, float(result.t_final), result.u_final,
                       result.diagnostics, result.episodes, result.bounces, merge_time)


def physics_for(config, t_final: float, u_final, diag, episodes, bounces,
                merge_time: float | None = None) -> Physics:
    """The Physics of a run of ``config`` that reached ``t_final`` in state ``u_final``
    (``physics_of`` without a Result: a sweep point, a run file's summary)."""
    c = wave_speed(config)
    tau = flight_time(config) if merge_time is None else float(merge_time)
    if not tau > 0:
        raise ValueError(f"merge_time = {merge_time!r} is out of range (seconds > 0)")
    u_final = np.asarray(u_final)
    in_contact = bool(u_final.size and u_final[0] < 0)
    start = math.nan
    if in_contact:
        start = _open_episode_start(diag, episodes, bounces)
    return Physics(float(config.gravity.g), c, lift_energy(config), float(t_final),
                   tau, in_contact, start)


def _open_episode_start(diag, episodes, bounces) -> float:
    """Start of the contact episode still running at the end of the run: the first
    diagnostics sample with u_0 < 0 after the last finished episode, back to the linear
    root of u_0 between it and the sample before (the first bounce's impact if no episode
    finished)."""
    t_ends = episodes["t_end"]
    if t_ends.size == 0 and bounces["t_impact"].size:
        return float(bounces["t_impact"][0])
    after = t_ends[-1] if t_ends.size else -math.inf
    t, u = diag["t"], diag["u_bottom"]
    idx = np.flatnonzero((t > after) & (u < 0))
    if idx.size == 0:
        return float(after) if math.isfinite(after) else 0.0
    k = int(idx[0])
    if k == 0 or t[k - 1] <= after:
        return float(t[k])
    return float(t[k - 1] + (t[k] - t[k - 1]) * u[k - 1] / (u[k - 1] - u[k]))


def energy_vibration(diag) -> np.ndarray:
    """Kinetic + stretch + bending energy about the centre of mass:
    ``energy_kinetic - w²/2 + energy_stretch + energy_bend`` (total mass 1).  It is >= 0,
    and constant in free flight at μ = 0 (uniform gravity does no work on it).

    Parameters
    ----------
    diag : dict of str to numpy.ndarray
        Diagnostics columns with ``cm_velocity``, ``energy_kinetic``, ``energy_stretch``
        and ``energy_bend``.

    Returns
    -------
    numpy.ndarray
        The vibration energy [J] per sample.
    """
    w = np.asarray(diag["cm_velocity"])
    return (np.asarray(diag["energy_kinetic"]) - 0.5 * w * w
            + np.asarray(diag["energy_stretch"]) + np.asarray(diag["energy_bend"]))


def merge_episodes(t_start, t_end, merge_time: float) -> list[tuple[int, int]]:
    """Groups ``(first, last)`` of episode indices whose gaps ``t_start[k+1] - t_end[k]``
    are all shorter than ``merge_time`` (the micro-contacts of one impact).

    Parameters
    ----------
    t_start, t_end : array_like
        Start and end times of the contact episodes [s], in order.
    merge_time : float
        Gaps shorter than this [s] merge.

    Returns
    -------
    list of (int, int)
        The first and last episode index of each group.
    """
    t_start, t_end = np.asarray(t_start), np.asarray(t_end)
    if t_start.size == 0:
        return []
    cut = np.flatnonzero(t_start[1:] - t_end[:-1] >= merge_time)
    firsts = np.concatenate([[0], cut + 1])
    lasts = np.concatenate([cut, [t_start.size - 1]])
    return [(int(a), int(b)) for a, b in zip(firsts, lasts)]


def flight_groups(diag, phys: Physics, t_s, t_e) -> list[tuple[int, int]]:
    """Groups ``(first, last)`` of episode indices, one per bounce: a group ends at a
    release followed by a flight, the bottom off the floor for at least
    ``phys.flight_time`` and the centre of mass turning over before the next contact (in
    free flight w = w_release + g (t − t_release): w_release > 0 and, for g < 0, the
    apex t_release + w_release/|g| before the next contact).  The rule of the compiled
    tracker (``stepping.events``), here with the release velocity from the diagnostics
    sample nearest after the release (a gap holding no sample is no flight)."""
    if len(t_s) == 0:
        return []
    out = [(0, 0)]
    for k in range(1, len(t_s)):
        t_rel, t_next = float(t_e[k - 1]), float(t_s[k])
        flight = False
        if t_next - t_rel >= phys.flight_time:
            st = _flight_state(diag, phys.g, t_rel, t_rel, t_next, before=False)
            w_r = st[0] if st is not None else -1.0
            flight = w_r > 0 and (phys.g >= 0 or t_rel + w_r / -phys.g < t_next)
        if flight:
            out.append((k, k))
        else:
            out[-1] = (out[-1][0], k)
    return out


def _flight_state(diag, g: float, t: float, lo: float, hi: float, before: bool):
    """(w, z, energy_vibration) at time ``t`` carried along the free-flight parabola from
    the diagnostics sample nearest to ``t`` inside the flight (lo, hi): the last one at or
    before ``t`` (``before``) or the first one at or after it.  None without such a
    sample."""
    ts = diag["t"]
    if before:
        idx = np.flatnonzero((ts <= t) & (ts > lo))
        if idx.size == 0:
            return None
        k = int(idx[-1])
    else:
        idx = np.flatnonzero((ts >= t) & (ts < hi))
        if idx.size == 0:
            return None
        k = int(idx[0])
    d = t - ts[k]
    w_s, z_s = diag["cm_velocity"][k], diag["cm_height"][k]
    ev = energy_vibration({c: diag[c][k:k + 1] for c in
                           ("cm_velocity", "energy_kinetic", "energy_stretch", "energy_bend")})
    return float(w_s + g * d), float(z_s + w_s * d + 0.5 * g * d * d), float(ev[0])


def _check_sampling(diag) -> float:
    """The largest spacing of the diagnostics samples (ValueError without samples)."""
    ts = np.asarray(diag["t"])
    if ts.size < 2:
        raise ValueError("the macroscopic-contact observables need diagnostics samples "
                         "(output.diagnostics_interval > 0)")
    return float(np.max(np.diff(ts)))


def macroscopic_contacts(diag, episodes, bounces, phys: Physics) -> dict[str, np.ndarray]:
    """One row per macroscopic contact, the episodes of one bounce (``flight_groups``:
    a contact ends at a release followed by ``phys.flight_time`` off the floor and a
    turn-over of the centre of mass), so
    every macroscopic impact has w_impact < 0; an episode still running at the end of the
    run belongs to the last, ``open``.  Columns: ``t_impact``, ``t_release`` (NaN if open),
    ``n_episodes``, ``w_impact``, ``w_release``, ``z_impact``, ``z_release``,
    ``ev_impact``, ``ev_release`` (energy_vibration at its ends), ``restitution``
    (-w_release/w_impact), ``restitution_apex``, ``rebound_speed`` (largest w sampled from
    the impact to the release, or to the end), ``min_u0``, ``max_floor_force``,
    ``vibration_ratio`` (energy_vibration over the rigid-body kinetic energy w²/2 at the
    impact: above 1 the bounce is driven by the vibration more than by the fall) and
    ``open``.

    Parameters
    ----------
    diag : dict of str to numpy.ndarray
        The run's diagnostics columns (``Result.diagnostics``).
    episodes : dict of str to numpy.ndarray
        Its contact episodes, ``t_start`` and ``t_end`` (``Result.episodes``).
    bounces : dict of str to numpy.ndarray
        Its bounce table (``Result.bounces``).
    phys : Physics
        The configuration's numbers, from ``physics_of``.

    Returns
    -------
    dict of str to numpy.ndarray
        The columns above, one entry per macroscopic contact.

    Raises
    ------
    ValueError
        Fewer than two diagnostics samples.
    """
    _check_sampling(diag)
    t_s = np.asarray(episodes["t_start"], float)
    t_e = np.asarray(episodes["t_end"], float)
    if phys.in_contact:
        t_s = np.append(t_s, phys.contact_start)
        t_e = np.append(t_e, math.nan)
    groups = flight_groups(diag, phys, t_s, t_e)
    names = ("t_impact", "t_release", "n_episodes", "w_impact", "w_release", "z_impact",
             "z_release", "ev_impact", "ev_release", "restitution", "restitution_apex",
             "rebound_speed", "min_u0", "max_floor_force", "vibration_ratio", "open")
    rows = {k: [] for k in names}
    ts, w_all = diag["t"], diag["cm_velocity"]
    b_imp, b_rel = np.asarray(bounces["t_impact"]), np.asarray(bounces["t_release"])
    b_open = np.asarray(bounces.get("open", np.zeros(b_imp.size, bool)), bool)
    for n, (a, b) in enumerate(groups):
        t_imp, t_rel = float(t_s[a]), float(t_e[b])
        is_open = math.isnan(t_rel)
        prev_end = float(t_e[a - 1]) if a > 0 else -math.inf
        next_start = float(t_s[b + 1]) if b + 1 < t_s.size else math.inf
        before = _flight_state(diag, phys.g, t_imp, prev_end, t_imp, before=True)
        if before is None:    # the run starts in contact: the initial sample is the impact
            k = 0
            before = (float(w_all[k]), float(diag["cm_height"][k]),
                      float(energy_vibration({c: diag[c][:1] for c in (
                          "cm_velocity", "energy_kinetic", "energy_stretch",
                          "energy_bend")})[0]))
        after = None if is_open else _flight_state(diag, phys.g, t_rel, t_rel, next_start,
                                                   before=False)
        if after is None and not is_open:   # released at the very end of the run
            k = int(np.argmin(np.abs(ts - t_rel)))
            after = (float(w_all[k]), float(diag["cm_height"][k]), math.nan)
        w_i, z_i, ev_i = before
        w_r, z_r, ev_r = after if after is not None else (math.nan, math.nan, math.nan)
        end = phys.t_final if is_open else t_rel
        inside = (ts >= t_imp) & (ts <= end)
        rebound = max(0.0, float(np.max(w_all[inside]))) if inside.any() else 0.0
        if not is_open:
            rebound = max(rebound, w_r)
        # extremes: the samples, and the per-step extremes of the bounces lying inside
        u_in = diag["u_bottom"][inside]
        f_in = diag["floor_force"][inside]
        full = (b_imp >= t_imp) & ((b_rel <= end) | (b_open & is_open))
        u_parts = [u_in, np.asarray(bounces["min_u0"], float)[full]]
        f_parts = [f_in, np.asarray(bounces["max_floor_force"], float)[full]]
        u_all, f_all = np.concatenate(u_parts), np.concatenate(f_parts)
        min_u0 = float(np.min(u_all)) if u_all.size else math.nan
        max_ff = float(np.max(f_all)) if f_all.size else math.nan
        e = -w_r / w_i if (not is_open and w_i < 0) else math.nan
        rows["t_impact"].append(t_imp)
        rows["t_release"].append(t_rel)
        rows["n_episodes"].append(b - a + 1)
        rows["w_impact"].append(w_i)
        rows["w_release"].append(w_r)
        rows["z_impact"].append(z_i)
        rows["z_release"].append(z_r)
        rows["ev_impact"].append(ev_i)
        rows["ev_release"].append(ev_r)
        rows["restitution"].append(e)
        rows["restitution_apex"].append(_apex_restitution(phys.g, w_i, z_i, w_r, z_r)
                                        if not is_open else math.nan)
        rows["rebound_speed"].append(rebound)
        rows["min_u0"].append(min_u0)
        rows["max_floor_force"].append(max_ff)
        rows["vibration_ratio"].append(ev_i / (0.5 * w_i * w_i) if w_i else math.inf)
        rows["open"].append(is_open)
    out = {k: np.asarray(v, dtype=float) for k, v in rows.items()}
    out["n_episodes"] = out["n_episodes"].astype(np.int64)
    out["open"] = out["open"].astype(bool)
    return out


def _apex_restitution(g: float, w_i: float, z_i: float, w_r: float, z_r: float) -> float:
    """sqrt((z_apex_after − ½)/(z_apex_before − ½)) with the apexes of the free-flight
    parabolas through the impact and the release, z_apex = z + w²/(2|g|), and ½ the
    centre-of-mass height of the undeformed rod standing on the floor; multiplied by 2|g|
    this reads sqrt((w_r² + 2|g|(z_r − ½)) / (w_i² + 2|g|(z_i − ½))), which is also its
    value at g = 0 (the rigid-body kinetic-energy ratio).  NaN for g > 0."""
    if g > 0 or w_i >= 0:
        return math.nan
    a = -2.0 * g
    num = w_r * w_r + a * (z_r - 0.5)
    den = w_i * w_i + a * (z_i - 0.5)
    if not den > 0:
        return math.nan
    return math.sqrt(max(num, 0.0) / den)


@dataclass
class FirstImpact:
    """The first macroscopic contact (``first_impact``; MODEL.md §3).

    Attributes
    ----------
    status : str
        One of STATUSES: ``"lift-off"``, ``"no lift-off"``, ``"open"``, ``"no impact"``.
    reason : str
        Why a value is missing or zero (empty after a lift-off).
    restitution : float
        −w_release/w_impact of the centre-of-mass velocity (0 without lift-off).
    restitution_apex : float
        sqrt of the rebound over the drop apex height of the centre of mass above 1/2.
    contact_time : float
        t_release − t_impact [s] (inf without lift-off).
    t_impact, t_release : float
        Start and end of the contact [s].
    n_episodes : int
        Contact episodes merged into it.
    w_impact, w_release : float
        Centre-of-mass velocity at its start and end [m s⁻¹].
    rebound_speed : float
        Largest centre-of-mass velocity from the impact to the release [m s⁻¹].
    min_u0 : float
        Deepest penetration, the lowest u_0 during the contact [m].
    max_floor_force : float
        Largest floor force during the contact [N].
    energy_vibration_impact, energy_vibration_release : float
        ``energy_vibration`` at its start and end [J].
    """

    status: str
    reason: str
    restitution: float
    restitution_apex: float
    contact_time: float
    t_impact: float
    t_release: float
    n_episodes: int
    w_impact: float
    w_release: float
    rebound_speed: float
    min_u0: float
    max_floor_force: float
    energy_vibration_impact: float
    energy_vibration_release: float

    def to_dict(self) -> dict:
        """Every attribute as plain values (``dataclasses.asdict``).

        Returns
        -------
        dict
        """
        return asdict(self)


def first_impact(diag, episodes, bounces, phys: Physics) -> FirstImpact:
    """The first macroscopic contact and its restitutions (see docs/MODEL.md §3).

    ``lift-off``: the contact ended; ``no lift-off``: it is still running at the end and the
    energy left is below ``phys.lift_energy``, so it can never end (restitution 0, apex
    restitution 0, contact time inf, the rebound speed of the centre of mass reported);
    ``open``: still running but the rod has energy enough to leave (NaN: run longer);
    ``no impact``: the rod never touched the floor.

    Parameters
    ----------
    diag : dict of str to numpy.ndarray
        The run's diagnostics columns (``Result.diagnostics``).
    episodes : dict of str to numpy.ndarray
        Its contact episodes, ``t_start`` and ``t_end`` (``Result.episodes``).
    bounces : dict of str to numpy.ndarray
        Its bounce table (``Result.bounces``).
    phys : Physics
        The configuration's numbers, from ``physics_of``.

    Returns
    -------
    FirstImpact
    """
    nan = math.nan
    rows = macroscopic_contacts(diag, episodes, bounces, phys)
    if rows["t_impact"].size == 0:
        return FirstImpact("no impact", f"the bottom never touched the floor before "
                           f"t = {phys.t_final:g}", nan, nan, nan, nan, nan, 0, nan, nan,
                           nan, nan, nan, nan, nan)
    r = {k: v[0] for k, v in rows.items()}
    common = dict(t_impact=float(r["t_impact"]), n_episodes=int(r["n_episodes"]),
                  w_impact=float(r["w_impact"]), rebound_speed=float(r["rebound_speed"]),
                  min_u0=float(r["min_u0"]), max_floor_force=float(r["max_floor_force"]),
                  energy_vibration_impact=float(r["ev_impact"]))
    if not r["open"]:
        return FirstImpact("lift-off", "", float(r["restitution"]),
                           float(r["restitution_apex"]),
                           float(r["t_release"] - r["t_impact"]), t_release=float(r["t_release"]),
                           w_release=float(r["w_release"]),
                           energy_vibration_release=float(r["ev_release"]), **common)
    e_end = float(diag["energy_total"][-1])
    if e_end < phys.lift_energy:
        ratio = common["rebound_speed"] / abs(common["w_impact"]) if common["w_impact"] else nan
        return FirstImpact("no lift-off",
                           f"the rod never leaves the floor: its energy {e_end:.6g} at "
                           f"t = {float(diag['t'][-1]):g} is below the {phys.lift_energy:.6g} "
                           f"a lift-off needs; the centre of mass rebounds at "
                           f"{common['rebound_speed']:.3g} ({ratio:.3g} of the impact speed)",
                           0.0, 0.0, math.inf, t_release=math.inf, w_release=nan,
                           energy_vibration_release=nan, **common)
    return FirstImpact("open", f"the first contact is still running at t = {phys.t_final:g} "
                       f"with energy {e_end:.6g} above the {phys.lift_energy:.6g} a lift-off "
                       f"needs: run longer (time.t_end)", nan, nan, nan,
                       t_release=nan, w_release=nan, energy_vibration_release=nan, **common)


def observables(result, merge_time: float | None = None) -> dict:
    """The scalar OBSERVABLES of a Result, with ``status`` and ``reason`` of the first
    macroscopic contact.

    Parameters
    ----------
    result : Result
        A run, from ``simulate`` or ``load_file``.
    merge_time : float, optional
        The flight time τ [s] that ends a macroscopic contact; by default π h/c, the one
        the bounce table uses (``physics_of``).
    """
    phys = physics_of(result, merge_time)
    d = result.diagnostics
    fi = first_impact(d, result.episodes, result.bounces, phys)
    ev, w = fi.energy_vibration_release, fi.w_release
    share = ev / (ev + 0.5 * w * w) if fi.status == "lift-off" else math.nan
    b = result.bounces
    min_u0 = min([float(np.min(d["u_bottom"]))] +
                 [float(x) for x in np.asarray(b["min_u0"])]) if d["t"].size else math.nan
    max_ff = max([float(np.max(d["floor_force"]))] +
                 [float(x) for x in np.asarray(b["max_floor_force"])]) if d["t"].size else math.nan
    return {"restitution_first": fi.restitution, "restitution_apex_first": fi.restitution_apex,
            "contact_time_first": fi.contact_time, "rebound_speed_first": fi.rebound_speed,
            "min_u0_first": fi.min_u0, "max_floor_force_first": fi.max_floor_force,
            "vibration_share_first": share, "min_u0": min_u0, "max_floor_force": max_ff,
            "status": fi.status, "reason": fi.reason}


# the diagnostics columns the first-impact observables read: a few floats per sample,
# whatever N is
TRACK_COLUMNS = ("t", "cm_velocity", "cm_height", "energy_kinetic", "energy_stretch",
                 "energy_bend", "u_bottom", "floor_force", "energy_total")


class ImpactTrack:
    """What the first-impact observables need of a run, kept as its blocks drain: the
    TRACK_COLUMNS of every diagnostics sample (9 floats, 72 bytes a sample, independent of
    N: 0.36 MB for the 5 s of the paper's runs at the default 1 ms interval) and the
    episode rows (2 floats each).  A sweep point and a run writer keep one beside their
    Extremes, ``summarize`` fills one from a file: the same numbers either way."""

    def __init__(self):
        from .columns import DIAG_COLUMNS

        self._idx = [DIAG_COLUMNS.index(c) for c in TRACK_COLUMNS]
        self._diag: list[np.ndarray] = []
        self._episodes: list[np.ndarray] = []

    def diagnostics(self, rows) -> None:
        """Keep the TRACK_COLUMNS of a block of diagnostics rows (``DIAG_COLUMNS``)."""
        rows = np.asarray(rows)
        if rows.shape[0]:
            self._diag.append(np.array(rows[:, self._idx], dtype=float))

    def episodes(self, rows) -> None:
        rows = np.asarray(rows)
        if rows.shape[0]:
            self._episodes.append(np.array(rows[:, :2], dtype=float))

    def read(self, f, n_diag: int, n_episodes: int) -> None:
        """Fill from the first rows of an open run file's diagnostics and episodes."""
        g = f["diagnostics"]
        if n_diag:
            self._diag.append(np.stack([np.asarray(g[c][:n_diag], float)
                                        for c in TRACK_COLUMNS], axis=1))
        e = f["episodes"]
        if n_episodes:
            self._episodes.append(np.stack([np.asarray(e[c][:n_episodes], float)
                                            for c in ("t_start", "t_end")], axis=1))

    def arrays(self) -> tuple[dict, dict]:
        """(diagnostics columns, episode columns) kept so far."""
        d = (np.concatenate(self._diag) if self._diag
             else np.zeros((0, len(TRACK_COLUMNS))))
        e = np.concatenate(self._episodes) if self._episodes else np.zeros((0, 2))
        return ({c: d[:, j] for j, c in enumerate(TRACK_COLUMNS)},
                {"t_start": e[:, 0], "t_end": e[:, 1]})


# the sweep summary columns of the first bounce: name -> (dtype, description)
IMPACT_COLUMNS: dict[str, tuple[str, str]] = {
    "restitution_first": ("float", "-w_release/w_impact of the first bounce (the first "
                                   "physical impact); 0 for no lift-off, NaN if open or no "
                                   "impact"),
    "impact_status": ("str", "first bounce: lift-off | no lift-off | open | no impact | "
                             "undefined"),
    "impact_reason": ("str", "why restitution_first is 0 or missing ('' for lift-off)"),
    "restitution_apex": ("float", "sqrt of rebound over drop apex height of the centre of "
                                  "mass above 1/2 for the first bounce"),
    "contact_time_first": ("float", "t_release - t_impact of the first bounce (inf: no "
                                    "lift-off)"),
    "w_impact": ("float", "centre-of-mass velocity at the first impact"),
    "rebound_speed": ("float", "largest centre-of-mass velocity from the first impact to "
                               "its release (to the end of the run without lift-off)"),
    "min_u0_impact": ("float", "deepest penetration min u_0 in the first bounce"),
    "vibration_ratio": ("float", "energy_vibration / (w_impact^2/2) at the first impact"),
}


def impact_values(config, t_final: float, u_final, track: ImpactTrack, bounces) -> dict:
    """The IMPACT_COLUMNS of a run from what ``track`` kept and its bounce table; status
    ``undefined`` with the reason when they cannot be evaluated (no diagnostics)."""
    out = {"restitution_first": math.nan, "impact_status": "undefined",
           "impact_reason": "", "restitution_apex": math.nan,
           "contact_time_first": math.nan, "w_impact": math.nan, "rebound_speed": math.nan,
           "min_u0_impact": math.nan, "vibration_ratio": math.nan}
    diag, episodes = track.arrays()
    try:
        phys = physics_for(config, t_final, u_final, diag, episodes, bounces)
        fi = first_impact(diag, episodes, bounces, phys)
    except ValueError as exc:
        out["impact_reason"] = str(exc)
        return out
    ratio = math.nan
    if fi.status != "no impact" and fi.w_impact:
        ratio = fi.energy_vibration_impact / (0.5 * fi.w_impact * fi.w_impact)
    out.update(restitution_first=fi.restitution, impact_status=fi.status,
               impact_reason=fi.reason, restitution_apex=fi.restitution_apex,
               contact_time_first=fi.contact_time, w_impact=fi.w_impact, rebound_speed=fi.rebound_speed,
               min_u0_impact=fi.min_u0, vibration_ratio=ratio)
    return out


def impact_line(values: dict) -> str:
    """One line for a report: 'first impact: e = 0.126 (lift-off), contact 0.0121 s, ...'
    or 'first impact: no lift-off (rebound speed 0.17 of impact)'."""
    st = values["impact_status"]
    if st == "lift-off":
        return (f"e = {values['restitution_first']:.4g} (lift-off), contact "
                f"{values['contact_time_first']:.4g} s, apex e = "
                f"{values['restitution_apex']:.4g}, penetration "
                f"{-values['min_u0_impact']:.4g}")
    if st == "no lift-off":
        ratio = values["rebound_speed"] / abs(values["w_impact"])
        return (f"e = 0 (no lift-off: rebound speed of the centre of mass {ratio:.3g} of "
                f"impact), penetration {-values['min_u0_impact']:.4g}")
    return f"{st}: {values['impact_reason']}"
