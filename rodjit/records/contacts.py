"""Macroscopic contacts and the first impact, from a run's arrays (docs/MODEL.md §3).

The compiled event tracking splits a run into contact *episodes* (``u_0 < 0``) and
*bounces*, one per physical impact: a bounce ends at a *flight*, a release after which the
bottom stays off the floor for at least τ = π h/c (``physics.flight_time``, the period of
the highest mode of the semi-discrete rod) and the centre of mass turns over (it leaves
rising and comes back falling).  Here the same rule (``flight_groups``) groups a run's
episodes into *macroscopic contacts*, one per bounce, for any τ, and the first-impact
observables (``first_impact``) are read at their ends, with the centre-of-mass state
carried to the contact's end points along the exact free-flight parabola from the nearest
diagnostics sample in flight.

Everything here is plain NumPy over a run's diagnostics, episode and bounce arrays; the
few numbers that come from the configuration travel in a ``Physics`` tuple
(``physics.physics_of``).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from .impact import NO_SAMPLES
from .physics import Physics

__all__ = ["energy_vibration", "merge_episodes", "flight_groups", "macroscopic_contacts",
           "FirstImpact", "first_impact", "STATUSES"]

# what ``first_impact`` reports of the first contact; one still open at the end with
# E(t_end) below the lift-off energy can never end ("no lift-off")
STATUSES = ("lift-off", "no lift-off", "open", "no impact")


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
        raise ValueError(NO_SAMPLES)
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
    rows: dict[str, list[float]] = {k: [] for k in names}
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


def first_impact(diag, episodes, bounces, phys: Physics, index: int = 0,
                 rows: dict[str, np.ndarray] | None = None) -> FirstImpact:
    """The first macroscopic contact and its restitutions (see docs/MODEL.md §3), or with
    ``index`` = k the (k+1)-th, with the same statuses.

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
    index : int
        Which macroscopic contact, from 0 (the first).
    rows : dict, optional
        The run's ``macroscopic_contacts``, where the caller has them already.

    Returns
    -------
    FirstImpact
    """
    nan = math.nan
    if rows is None:
        rows = macroscopic_contacts(diag, episodes, bounces, phys)
    if rows["t_impact"].size <= index:
        what = ("the bottom never touched the floor" if index == 0 else
                f"{rows['t_impact'].size} macroscopic contact(s), not {index + 1},")
        return FirstImpact("no impact", f"{what} before t = {phys.t_final:g}", nan, nan,
                           nan, nan, nan, 0, nan, nan, nan, nan, nan, nan, nan)
    r = {k: v[index] for k, v in rows.items()}
    common: dict[str, Any] = dict(
        t_impact=float(r["t_impact"]), n_episodes=int(r["n_episodes"]),
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
    which = "first contact" if index == 0 else f"contact {index + 1}"
    return FirstImpact("open", f"the {which} is still running at t = {phys.t_final:g} "
                       f"with energy {e_end:.6g} above the {phys.lift_energy:.6g} a lift-off "
                       f"needs: run longer (time.t_end)", nan, nan, nan,
                       t_release=nan, w_release=nan, energy_vibration_release=nan, **common)
