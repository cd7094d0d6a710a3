"""The coefficients of the embedded explicit Runge–Kutta pairs (``integrators.erk``) and
what follows from them, computed once in NumPy: each pair's tableau, its continuous
extension, the stretches of the imaginary and negative real axes inside the stability
regions of the step and of its extension, and the step caps these give.

Keyed by the integrator's name (``"dp54"``, ``"dop853"``); ``erk`` keys them by its
parameter classes.  Nothing here is compiled.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["Tableau", "Dense", "TABLEAUS", "DENSE", "DENSE_TERMS_MAX", "DENSE_GROWTH",
           "IMAG_SAFETY", "STABILITY_CAP", "VISCOUS_CAP", "stability_polynomial",
           "imaginary_limit", "dense_amplification", "dense_limits", "dense_rows", "work_rows"]


_A54 = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0],
    [0.2, 0.0, 0.0, 0.0, 0.0],
    [0.075, 0.225, 0.0, 0.0, 0.0],
    [0.9777777777777777, -3.7333333333333334, 3.5555555555555554, 0.0, 0.0],
    [2.9525986892242035, -11.595793324188385, 9.822892851699436, -0.2908093278463649, 0.0],
    [2.8462752525252526, -10.757575757575758, 8.906422717743473, 0.2784090909090909,
     -0.2735313036020583]])
_B54 = np.array([0.09114583333333333, 0.0, 0.44923629829290207, 0.6510416666666666,
                 -0.322376179245283, 0.13095238095238096])
_E54 = np.array([-0.0012326388888888888, 0.0, 0.0042527702905061394, -0.03697916666666667,
                 0.05086379716981132, -0.0419047619047619, 0.025])

_A853 = np.array([
    [0.0] * 11,
    [0.05260015195876773] + [0.0] * 10,
    [0.0197250569845379, 0.0591751709536137] + [0.0] * 9,
    [0.02958758547680685, 0.0, 0.08876275643042054] + [0.0] * 8,
    [0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792] + [0.0] * 7,
    [0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242] + [0.0] * 6,
    [0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125]
    + [0.0] * 5,
    [0.03709200011850479, 0.0, 0.0, 0.17038392571223998, 0.10726203044637328,
     -0.015319437748624402, 0.008273789163814023] + [0.0] * 4,
    [0.6241109587160757, 0.0, 0.0, -3.3608926294469414, -0.868219346841726,
     27.59209969944671, 20.154067550477894, -43.48988418106996] + [0.0] * 3,
    [0.47766253643826434, 0.0, 0.0, -2.4881146199716677, -0.590290826836843,
     21.230051448181193, 15.279233632882423, -33.28821096898486, -0.020331201708508627]
    + [0.0] * 2,
    [-0.9371424300859873, 0.0, 0.0, 5.186372428844064, 1.0914373489967295,
     -8.149787010746927, -18.52006565999696, 22.739487099350505, 2.4936055526796523,
     -3.0467644718982196, 0.0],
    [2.273310147516538, 0.0, 0.0, -10.53449546673725, -2.0008720582248625,
     -17.9589318631188, 27.94888452941996, -2.8589982771350235, -8.87285693353063,
     12.360567175794303, 0.6433927460157636]])
_B853 = np.array([0.054293734116568765, 0.0, 0.0, 0.0, 0.0, 4.450312892752409,
                  1.8915178993145003, -5.801203960010585, 0.3111643669578199,
                  -0.1521609496625161, 0.20136540080403034, 0.04471061572777259])
_E5_853 = np.array([0.01312004499419488, 0.0, 0.0, 0.0, 0.0, -1.2251564463762044,
                    -0.4957589496572502, 1.6643771824549864, -0.35032884874997366,
                    0.3341791187130175, 0.08192320648511571, -0.022355307863886294, 0.0])
_E3_853 = np.array([-0.18980075407240762, 0.0, 0.0, 0.0, 0.0, 4.450312892752409,
                    1.8915178993145003, -5.801203960010585, -0.4226823213237919,
                    -0.1521609496625161, 0.20136540080403034, 0.02265179219836082, 0.0])


class Tableau(NamedTuple):
    """A pair's coefficients: ``a`` (s, s−1) strictly lower, ``b`` (s), the error weights
    ``e`` (s+1, the new point last), the second estimate ``e3`` of a combined norm (zeros
    for a plain one), ``combined`` and the order ``q`` of the error estimate."""

    a: np.ndarray
    b: np.ndarray
    e: np.ndarray
    e3: np.ndarray
    combined: bool
    q: int


TABLEAUS = {
    "dp54": Tableau(_A54, _B54, _E54, np.zeros(7), False, 4),
    "dop853": Tableau(_A853, _B853, _E5_853, _E3_853, True, 7),
}


def stability_polynomial(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Coefficients r_0 … r_s (lowest first) of an explicit pair's stability function
    R(z) = 1 + z bᵀ(I − zA)⁻¹1 = Σ_k bᵀA^(k−1)1 z^k: the amplification of y' = λy per step,
    z = λ dt."""
    s = b.size
    A = np.zeros((s, s))
    A[:, :a.shape[1]] = a[:s]
    r = [1.0]
    w = np.ones(s)
    for _ in range(s):
        r.append(float(b @ w))
        w = A @ w
    return np.array(r)


def imaginary_limit(a: np.ndarray, b: np.ndarray) -> float:
    """The largest y with |R(iy')| ≤ 1 for every 0 ≤ y' ≤ y: the stretch of the imaginary
    axis (undamped oscillation, z = iω dt) inside the stability region.  |R(iy)|² − 1 is
    a polynomial in y; its smallest positive root at which it turns positive."""
    r = stability_polynomial(a, b)
    p = np.polynomial.Polynomial(r * (1j) ** np.arange(r.size))
    m = (p * np.polynomial.Polynomial(p.coef.conj())).coef.real   # |R(iy)|², in y
    m[0] -= 1.0
    g = np.polynomial.Polynomial(m)
    roots = sorted(x.real for x in g.roots() if abs(x.imag) < 1e-9 * max(1.0, abs(x)) and
                   x.real > 1e-6)
    for y in roots:
        if g(y * (1.0 + 1e-6)) > 0.0:
            return float(y)
    return math.inf


# ---- dense output (module docstring): the extra stages' coefficients over every earlier
# stage (stage index: the pair's stages, the new point, the extra stages) and the weights
# d_mj of the terms R_m, as published in Hairer's dopri5.f and dop853.f
_D54 = np.array([[-12715105075.0 / 11282082432.0, 0.0, 87487479700.0 / 32700410799.0,
                  -10690763975.0 / 1880347072.0, 701980252875.0 / 199316789632.0,
                  -1453857185.0 / 822651844.0, 69997945.0 / 29380423.0]])
_AX853 = np.array([
    [0.056167502283047954, 0.0, 0.0, 0.0, 0.0, 0.0, 0.25350021021662483, -0.2462390374708025,
     -0.12419142326381637, 0.15329179827876568, 0.00820105229563469, 0.007567897660545699,
     -0.008298, 0.0, 0.0, 0.0],
    [0.03183464816350214, 0.0, 0.0, 0.0, 0.0, 0.028300909672366776, 0.053541988307438566,
     -0.05492374857139099, 0.0, 0.0, -0.00010834732869724932, 0.0003825710908356584,
     -0.00034046500868740456, 0.1413124436746325, 0.0, 0.0],
    [-0.42889630158379194, 0.0, 0.0, 0.0, 0.0, -4.697621415361164, 7.683421196062599,
     4.06898981839711, 0.3567271874552811, 0.0, 0.0, 0.0, -0.0013990241651590145,
     2.9475147891527724, -9.15095847217987, 0.0]])
_D853 = np.array([
    [-8.428938276109013, 0.0, 0.0, 0.0, 0.0, 0.5667149535193777, -3.0689499459498917,
     2.38466765651207, 2.117034582445028, -0.871391583777973, 2.2404374302607883,
     0.6315787787694688, -0.08899033645133331, 18.148505520854727, -9.194632392478356,
     -4.436036387594894],
    [10.427508642579134, 0.0, 0.0, 0.0, 0.0, 242.28349177525817, 165.20045171727028,
     -374.5467547226902, -22.113666853125306, 7.733432668472264, -30.674084731089398,
     -9.332130526430229, 15.697238121770845, -31.139403219565178, -9.35292435884448,
     35.81684148639408],
    [19.985053242002433, 0.0, 0.0, 0.0, 0.0, -387.0373087493518, -189.17813819516758,
     527.8081592054236, -11.57390253995963, 6.8812326946963, -1.0006050966910838,
     0.7777137798053443, -2.778205752353508, -60.19669523126412, 84.32040550667716,
     11.99229113618279],
    [-25.69393346270375, 0.0, 0.0, 0.0, 0.0, -154.18974869023643, -231.5293791760455,
     357.6391179106141, 93.40532418362432, -37.45832313645163, 104.0996495089623,
     29.8402934266605, -43.53345659001114, 96.32455395918828, -39.17726167561544,
     -149.72683625798564]])


class Dense(NamedTuple):
    """A pair's continuous extension: ``ax`` (extra stages, stages in all) the extra
    stages' coefficients over every earlier stage, ``d`` (terms, stages in all) the weights
    of R₅, R₆, …; both indexed by stage index (the pair's stages, the new point, the extra
    stages)."""

    ax: np.ndarray
    d: np.ndarray


DENSE = {
    "dp54": Dense(np.zeros((0, 7)), _D54),
    "dop853": Dense(_AX853, _D853),
}
# ``dense_dissipated`` sums the terms R₅ … R₈ in four accumulators
DENSE_TERMS_MAX = 4
if any(t.d.shape[0] > DENSE_TERMS_MAX for t in DENSE.values()):
    raise ValueError(f"a dense output has more than {DENSE_TERMS_MAX} terms R_m")


def dense_rows(name) -> int:
    """The first work row of the dense-output terms R_m (after every stage's rows)."""
    return 2 * DENSE[name].d.shape[1]


def work_rows(name) -> int:
    """Scratch rows the pair needs: S, K and two per stage after the first (the new point's
    two, the height of an extra stage and a spare row), then two per dense-output term (a
    pair with a dense output)."""
    if name not in DENSE:
        return 2 * TABLEAUS[name].b.size
    return dense_rows(name) + 2 * DENSE[name].d.shape[0]


def dense_amplification(name, z, thetas) -> np.ndarray:
    """|y(θ)| of the pair's continuous extension applied to y' = λy from y⁰ = 1 over one
    step, z = λ dt (an array), at each θ of ``thetas``: shape (len(z), len(thetas)).  A
    value above 1 at an interior θ is a mode the interpolated rows show grown, although
    the step itself (θ = 1, |R(z)|) damps it."""
    t, ext = TABLEAUS[name], DENSE[name]
    z = np.asarray(z, dtype=complex)[:, None]
    ns = t.b.size
    A = np.zeros((ns, ns))
    A[:, :t.a.shape[1]] = t.a[:ns]
    k = np.zeros((z.shape[0], ext.d.shape[1]), dtype=complex)   # dt·f at each stage
    for i in range(ns):
        k[:, i] = z[:, 0] * (1.0 + k[:, :i] @ A[i, :i])
    y1 = 1.0 + k[:, :ns] @ t.b
    k[:, ns] = z[:, 0] * y1                                      # the new point
    for m in range(ext.ax.shape[0]):
        j = ns + 1 + m
        k[:, j] = z[:, 0] * (1.0 + k[:, :j] @ ext.ax[m, :j])
    r = k @ ext.d.T                                              # the terms R₅ …
    s = np.asarray(thetas, dtype=float)[None, :]
    s1 = 1.0 - s
    delta = (y1 - 1.0)[:, None]
    b = k[:, :1] - delta
    c = delta - k[:, ns:ns + 1] - b
    tail = np.zeros_like(delta * s)
    for m in range(r.shape[1] - 1, -1, -1):
        tail = (s1 if m % 2 == 0 else s) * (r[:, m:m + 1] + tail)
    return np.abs(1.0 + s * (delta + s1 * (b + s * (c + tail))))


# The largest growth a dense output may show a mode in its rows (1 %: the stiff
# components of a contact, whose steps sit at the cap, stay at their size between steps)
DENSE_GROWTH = 1.01
_THETAS = np.linspace(0.0, 1.0, 101)


def _first_exceeding(values, ok) -> float:
    """The last of ``values`` (increasing) before the first at which ``ok`` is False."""
    bad = np.flatnonzero(~ok)
    return float(values[bad[0] - 1]) if bad.size else math.inf


def dense_limits(name) -> tuple[float, float]:
    """``(y, x)``: the stretches [0, iy] of the imaginary axis (undamped modes, z = iω dt)
    and [−x, 0] of the negative real one (overdamped viscous modes) on which the pair's
    dense output grows no mode by more than ``DENSE_GROWTH`` (inf: not before the pair's
    own stability limit there).  Scanned in steps of 0.01 up to the stability limits."""
    t = TABLEAUS[name]
    y_stab = imaginary_limit(t.a, t.b)
    ys = np.arange(0.01, y_stab + 0.005, 0.01)
    y = _first_exceeding(ys, dense_amplification(name, 1j * ys, _THETAS).max(axis=1)
                         <= DENSE_GROWTH)
    r = stability_polynomial(t.a, t.b)
    xs = np.arange(0.01, 20.0, 0.01)
    stable = np.abs(np.polynomial.polynomial.polyval(-xs, r)) <= 1.0
    x_stab = _first_exceeding(xs, stable)
    xs = xs[xs <= x_stab]
    x = _first_exceeding(xs, dense_amplification(name, -xs, _THETAS).max(axis=1)
                         <= DENSE_GROWTH)
    return y, x


# An undamped mode whose ω dt leaves the pair's stretch of the imaginary axis grows every
# step (rounding seeds it even where the motion does not excite it) unseen by the error
# estimate until it is large: the pair's step is capped at this fraction of
# imaginary_limit / ω, ω the Gershgorin bound at the new state (itself above the highest
# frequency).  A pair with a dense output is capped also where its extension would grow a
# mode in the rows (``dense_limits``): on the imaginary axis through ω, and on the real
# axis through the Gershgorin bound 4μ/h² of the viscous term's rates (``VISCOUS_CAP``;
# every damped mode has |z| ≤ dt·max(ω, 4μ/h²), and the extensions grow none inside that
# half disc beyond what they do on its two axes, tests/test_stepping_dense.py).
IMAG_SAFETY = 0.9
_DENSE_LIMITS = {P: dense_limits(P) for P in DENSE}
STABILITY_CAP = {P: IMAG_SAFETY * min(imaginary_limit(t.a, t.b),
                                      _DENSE_LIMITS.get(P, (math.inf, math.inf))[0])
                 for P, t in TABLEAUS.items()}
VISCOUS_CAP = {P: IMAG_SAFETY * _DENSE_LIMITS.get(P, (math.inf, math.inf))[1]
               for P in TABLEAUS}
