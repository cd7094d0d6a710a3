"""Embedded explicit Runge–Kutta pairs: ``dp54`` (Dormand–Prince 5(4)) and ``dop853``
(Dormand–Prince 8(5,3)), with error control, for smooth motion at tight tolerances.

Both integrate the first-order form of MODEL.md §2, y = (u, v), y' = (v, a(u, v)), with
``a`` the full acceleration M⁻¹(−∇V(u) − μKv) (``energy.full_accel``).  A step of length
dt from yⁿ with stages k_j = f(Y_j), Y_j = yⁿ + dt Σ_{l<j} a_jl k_l, is

    yⁿ⁺¹ = yⁿ + dt Σ_j b_j k_j,       error estimate  dt Σ_j e_j k_j  (j up to the new point)

(the coefficients are Dormand and Prince's, as in Hairer, Nørsett & Wanner, *Solving
Ordinary Differential Equations I*, and SciPy's RK45/DOP853).  Both pairs are FSAL: the
last stage is f(yⁿ⁺¹), so the new state's derivative (v, a) is the state's own rows and the
next step reuses it; a resumed run reads it from the checkpointed state (``a`` row).

Error norm (Hairer's): the root mean square over all 2(N+1) components of u and v of the
error divided by atol + rtol·max(|yⁿ|, |yⁿ⁺¹|); for dop853 the combined 5th/3rd-order
estimate err₅²/√(err₅² + 0.01 err₃²).  ≤ 1 accepts; > 1 returns INACCURATE and the loop
retries at ``dt_suggest``.  The next step is dt·0.9·err^(−1/(q+1)), at least 0.2 dt (q = 4
for dp54, 7 for dop853); how much it may exceed the previous proposal is the loop's rule
(``control.PAIR_GROWTH``: 10× for dp54, 6× for dop853, none right after a rejection).  Under fixed steps (``time.dt``) the loop accepts every valid step.

Admissibility: every stage state is checked (ε > −1, u_0 > −β, finite); a stage outside
returns its failure code and the loop retries a quarter of the step.  The floor force has
a kink at u_0 = 0 (σ_b' jumps from 0 to 3κ_b/β), which the error estimate cannot see: a
pair stepping across it stalls near 1e-4, and a pair that only ends its accepted steps on
the crossings rejects trial after trial there.  So the loop (``loop.advance``) gives each
adaptive trial the floor law of the side its start is on (``laws.Sided``: σ_b ≡ 0, or the
contact branch continued past 0), a smooth force for which the estimate holds, and takes a
trial that leaves its side again, ending on the crossing.  The step's stages never see
the kink, whatever side they reach.

Explicit pairs are stability-bound: dt times every eigenvalue of the linearised system must
stay inside the pair's stability region (it reaches about −3.3 on the negative real axis for
dp54 and about −6 for dop853; viscosity adds real eigenvalues down to about −4μ/h², the
floor in contact frequencies from √(6κ_b/(βh)) up), so with stiff viscosity, a stiff floor
or a long rod the error controller keeps the step near that limit (rejecting the steps
that grow past it) and ``energy`` is the better choice.  On the imaginary axis (the
undamped oscillations of the rod) the regions reach only |z| ≈ 1.0 (dp54) and 6.0
(dop853) (``imaginary_limit``, from each tableau's stability polynomial).  A mode the
motion does not excite (the rod in free fall) leaves the error estimate blind to it, so
without a cap the steps of a free flight would grow until ω·dt is far outside, and the
rounding seeded in that mode would grow each step; the next step is therefore capped at
``STABILITY_CAP`` / ω, ω the Gershgorin bound at the new state (and, with viscosity, at
``VISCOUS_CAP`` · h²/(4μ): dense output below).

The energy is not conserved exactly: at μ = 0 it drifts by an amount that follows the
tolerance (tests/test_stepping_erk.py).  The dissipated energy is the pair's quadrature
of ∫2R(v) dt over the stages (weights b_j), consistent to the pair's order.

Dense output (``dense_setup``, ``dense``): after an accepted step from yⁿ at t to yⁿ⁺¹ at
t + dt, the pair's continuous extension gives y(t + θ dt), 0 ≤ θ ≤ 1, in Hairer's form

    y(θ) = yⁿ + θ(Δ + θ'(B + θ(C + θ'(R₅ + θ(R₆ + θ'(R₇ + θ R₈))))))      θ' = 1 − θ

with Δ = yⁿ⁺¹ − yⁿ, B = dt f(yⁿ) − Δ, C = Δ − dt f(yⁿ⁺¹) − B (a cubic Hermite part that
takes both ends and both slopes exactly) and R_m = dt Σ_j d_mj k_j over the stages.
``dp54``: the 4th-order extension of Shampine (1986) that Hairer's DOPRI5 uses (HNW I,
§II.6, "Dense output"; R₅ only, coefficients d_j of dopri5.f, the last column of SciPy's
RK45 interpolation matrix), free: it needs only the step's own stages.  ``dop853``: the
7th-order extension of Hairer's DOP853 (dop853.f; SciPy's ``dop853_coefficients``), R₅ … R₈
from the step's stages, its new point and three extra stages at c = 0.1, 0.2 and 7/9,
which ``dense_setup`` evaluates once for a step with an output time inside it (every
output of that step reuses them); an extra stage outside the admissible set returns its
failure code, and the loop retries the step shorter.  θ = 0 gives yⁿ exactly, θ = 1 gives
yⁿ⁺¹ to rounding (yⁿ + Δ).  An extension has its own stability function |y(θ)| for
y' = λy (``dense_amplification``): near the edge of the step's region dop853's reaches
about 15 at interior θ (z ≈ −6, and ±5.9i; uncapped, rows of the paper's runs at
rtol = atol = 1e-2 had 10⁴ times the initial energy), dp54's about 1.07 at −3.3.  The
caps of the next step (``STABILITY_CAP``, ``VISCOUS_CAP``) keep z where neither the step
nor its extension grows a mode by more than ``DENSE_GROWTH``.  The dissipated
energy D, D' = 2R(v), is the same extension of the step's quadrature
(``dense_dissipated``: the pair applied to the quadrature component, k_j = 2R of stage j's
velocity), so E + D at an interpolated row keeps the balance to the extension's order, and
D(1) is the step's own increment.  The extension's code is written for any pair in
``DENSE`` (extra stages, up to ``DENSE_TERMS_MAX`` terms R_m).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..kernels.forces import INACCURATE, NON_FINITE, OK, momentum
from .energy import full_accel
from .step_result import StepResult
from .._jit import kernel, overload, step_kernel

__all__ = ["DP54", "DOP853", "TABLEAUS", "DENSE", "tableau", "dense_tableau", "initial",
           "step", "dense_setup", "dense", "dense_dissipated", "work_rows", "dense_amplification",
           "dense_limits"]


class DP54(NamedTuple):
    """Dormand–Prince 5(4): six stages and the new point (FSAL), order 5."""

    rtol: float
    atol: float


class DOP853(NamedTuple):
    """Dormand–Prince 8(5,3): twelve stages and the new point (FSAL), order 8."""

    rtol: float
    atol: float


SAFETY = 0.9
FAC_MIN = 0.2

# rows of the scratch array ``work``: the stresses and curvatures of ``accel``, then for each
# stage j ≥ 1 its velocity (the u-derivative) and acceleration (the v-derivative); stage 0
# is the state's own (v, a), the new point (stage index s, s the number of stages) the
# trial's (v2, a2), and its two rows are free: row 2s holds the height of a dense-output
# extra stage (indices s + 1, …, rows as for the stages); after them, two rows (u and v
# parts) for each dense-output term R_m (``dense_rows``)
S = 0
K = 1


@step_kernel
def stage_rows(j):
    """The work rows (velocity, acceleration) of stage j ≥ 1."""
    return 2 * j, 2 * j + 1


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
    DP54: Tableau(_A54, _B54, _E54, np.zeros(7), False, 4),
    DOP853: Tableau(_A853, _B853, _E5_853, _E3_853, True, 7),
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
    DP54: Dense(np.zeros((0, 7)), _D54),
    DOP853: Dense(_AX853, _D853),
}
# ``dense_dissipated`` sums the terms R₅ … R₈ in four accumulators
DENSE_TERMS_MAX = 4
if any(t.d.shape[0] > DENSE_TERMS_MAX for t in DENSE.values()):
    raise ValueError(f"a dense output has more than {DENSE_TERMS_MAX} terms R_m")


def dense_rows(params_type) -> int:
    """The first work row of the dense-output terms R_m (after every stage's rows)."""
    return 2 * DENSE[params_type].d.shape[1]


def work_rows(params_type) -> int:
    """Scratch rows the pair needs: S, K and two per stage after the first (the new point's
    two, the height of an extra stage and a spare row), then two per dense-output term (a
    pair with a dense output)."""
    if params_type not in DENSE:
        return 2 * TABLEAUS[params_type].b.size
    return dense_rows(params_type) + 2 * DENSE[params_type].d.shape[0]


def dense_amplification(params_type, z, thetas) -> np.ndarray:
    """|y(θ)| of the pair's continuous extension applied to y' = λy from y⁰ = 1 over one
    step, z = λ dt (an array), at each θ of ``thetas``: shape (len(z), len(thetas)).  A
    value above 1 at an interior θ is a mode the interpolated rows show grown, although
    the step itself (θ = 1, |R(z)|) damps it."""
    t, ext = TABLEAUS[params_type], DENSE[params_type]
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


def dense_limits(params_type) -> tuple[float, float]:
    """``(y, x)``: the stretches [0, iy] of the imaginary axis (undamped modes, z = iω dt)
    and [−x, 0] of the negative real one (overdamped viscous modes) on which the pair's
    dense output grows no mode by more than ``DENSE_GROWTH`` (inf: not before the pair's
    own stability limit there).  Scanned in steps of 0.01 up to the stability limits."""
    t = TABLEAUS[params_type]
    y_stab = imaginary_limit(t.a, t.b)
    ys = np.arange(0.01, y_stab + 0.005, 0.01)
    y = _first_exceeding(ys, dense_amplification(params_type, 1j * ys, _THETAS).max(axis=1)
                         <= DENSE_GROWTH)
    r = stability_polynomial(t.a, t.b)
    xs = np.arange(0.01, 20.0, 0.01)
    stable = np.abs(np.polynomial.polynomial.polyval(-xs, r)) <= 1.0
    x_stab = _first_exceeding(xs, stable)
    xs = xs[xs <= x_stab]
    x = _first_exceeding(xs, dense_amplification(params_type, -xs, _THETAS).max(axis=1)
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


def tableau(scheme):
    t = TABLEAUS[type(scheme)]
    return t.a, t.b, t.e, t.e3, t.combined, t.q


def step_caps(scheme):
    """``(STABILITY_CAP, VISCOUS_CAP)`` of the scheme: the largest ω·dt and dt·4μ/h² its
    steps may take."""
    return STABILITY_CAP[type(scheme)], VISCOUS_CAP[type(scheme)]


@overload(step_caps)
def _step_caps_ov(scheme):
    caps = STABILITY_CAP[scheme.instance_class], VISCOUS_CAP[scheme.instance_class]
    return lambda scheme: caps


@step_kernel
def _capped(scheme, system, dt, om2):
    """``dt`` within the scheme's caps at the state whose Gershgorin bound of ω² is
    ``om2`` (module docstring)."""
    imag, visc = step_caps(scheme)
    if om2 > 0.0:
        dt = min(dt, imag / math.sqrt(om2))
    if system.mu > 0.0:
        dt = min(dt, visc * system.h * system.h / (4.0 * system.mu))
    return dt


@overload(tableau)
def _tableau_ov(scheme):
    t = TABLEAUS[scheme.instance_class]
    a, b, e, e3, combined, q = t.a, t.b, t.e, t.e3, t.combined, t.q
    return lambda scheme: (a, b, e, e3, combined, q)


def dense_tableau(scheme):
    t = DENSE[type(scheme)]
    return t.ax, t.d


@overload(dense_tableau)
def _dense_tableau_ov(scheme):
    t = DENSE[scheme.instance_class]
    ax, d = t.ax, t.d
    return lambda scheme: (ax, d)


@step_kernel
def _power(x, p):
    return math.pow(x, p)


@step_kernel
def _factor(err, q):
    """SAFETY·err^(−1/(q+1)), at least FAC_MIN.  No upper clamp here: the loop caps the
    growth over the previous *proposal* (``control.propose``), so a step cut short to land
    on an output time or a floor crossing (whose error is tiny) does not shrink the next."""
    if not err > 0.0:
        return np.inf
    return max(FAC_MIN, SAFETY * _power(err, -1.0 / (q + 1.0)))


@step_kernel
def _rate(system, v):
    """2R(v) = μ/h Σ (v_{i+1} − v_i)², the viscous dissipation rate."""
    r = 0.0
    for i in range(system.n):
        d = v[i + 1] - v[i]
        r += d * d
    return system.mu / system.h * r


@kernel
def initial(scheme, system, rod, floor, u, v, a, work):
    """Full acceleration of the initial state and Hairer's starting step: h0 = 0.01‖y‖/‖f‖,
    then from a trial Euler step the step whose error (‖f'‖ h^(q+1)) is 0.01, at most 100 h0,
    and at most ``STABILITY_CAP`` / ω (the stability limit of undamped oscillation)."""
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u, v, a, work[S], work[K],
                                            bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    _, _, _, _, _, q = tableau(scheme)
    n1 = u.size
    d0 = 0.0
    d1 = 0.0
    for i in range(n1):
        su = scheme.atol + scheme.rtol * abs(u[i])
        sv = scheme.atol + scheme.rtol * abs(v[i])
        d0 += (u[i] / su) ** 2 + (v[i] / sv) ** 2
        d1 += (v[i] / su) ** 2 + (a[i] / sv) ** 2
    m = 2.0 * n1
    d0 = math.sqrt(d0 / m)
    d1 = math.sqrt(d1 / m)
    h0 = 0.01 * d0 / d1 if d0 > 1e-5 and d1 > 1e-5 else 1e-6
    h0 = _capped(scheme, system, h0, om2)
    u1 = work[2]   # stage rows as scratch
    v1 = work[3]
    a1 = work[4]
    for i in range(n1):
        u1[i] = u[i] + h0 * v[i]
        v1[i] = v[i] + h0 * a[i]
    st1 = full_accel(system, rod, floor, u1, v1, a1, work[S], work[K], bool(False))[0]
    dt = h0
    if st1 == OK:
        d2 = 0.0
        for i in range(n1):
            su = scheme.atol + scheme.rtol * abs(u[i])
            sv = scheme.atol + scheme.rtol * abs(v[i])
            d2 += ((v1[i] - v[i]) / su) ** 2 + ((a1[i] - a[i]) / sv) ** 2
        d2 = math.sqrt(d2 / m) / h0
        dm = max(d1, d2)
        h1 = (max(1e-6, 1e-3 * h0) if dm <= 1e-15
              else _power(0.01 / dm, 1.0 / (q + 1.0)))
        dt = min(100.0 * h0, h1)
        if om2 > 0.0:
            dt = min(dt, 2.0 / math.sqrt(om2))
    return StepResult(OK, 0.0, emin, fl, dt, 0.0, 0.0)


@step_kernel
def step(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, sstats, dt):
    """Trial step from (u, v, a) into (u2, v2, a2); the inputs are never modified.

    Returns OK or INACCURATE (valid state, error estimate > 1: retry with ``dt_suggest``),
    or the failure code of the first stage outside the admissible set."""
    A, B, E, E3, combined, q = tableau(scheme)
    ns = B.size
    n1 = u.size
    diss = 0.0
    if system.mu > 0.0:
        diss = B[0] * _rate(system, v)
    # stages 1 … ns−1; the stage height goes into u2 (scratch until the new point)
    for j in range(1, ns):
        rv, ra = stage_rows(j)
        vj = work[rv]
        aj = work[ra]
        for i in range(n1):
            du = A[j, 0] * v[i]
            dv = A[j, 0] * a[i]
            for l in range(1, j):
                cl = A[j, l]
                if cl != 0.0:
                    du += cl * work[2 * l, i]
                    dv += cl * work[2 * l + 1, i]
            u2[i] = u[i] + dt * du
            vj[i] = v[i] + dt * dv
        status, val, emin, fl, _ = full_accel(system, rod, floor, u2, vj, aj, work[S],
                                              work[K], bool(False))
        if status != OK:
            return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
        if system.mu > 0.0 and B[j] != 0.0:
            diss += B[j] * _rate(system, vj)
    # the new point
    for i in range(n1):
        du = B[0] * v[i]
        dv = B[0] * a[i]
        for l in range(1, ns):
            cl = B[l]
            if cl != 0.0:
                du += cl * work[2 * l, i]
                dv += cl * work[2 * l + 1, i]
        u2[i] = u[i] + dt * du
        v2[i] = v[i] + dt * dv
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u2, v2, a2, work[S],
                                            work[K], bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    # error norm over u and v (module docstring)
    e5 = 0.0
    e3 = 0.0
    for i in range(n1):
        eu = E[0] * v[i] + E[ns] * v2[i]
        ev = E[0] * a[i] + E[ns] * a2[i]
        fu = E3[0] * v[i] + E3[ns] * v2[i]
        fv = E3[0] * a[i] + E3[ns] * a2[i]
        for l in range(1, ns):
            cl = E[l]
            if cl != 0.0:
                eu += cl * work[2 * l, i]
                ev += cl * work[2 * l + 1, i]
            if combined:
                c3 = E3[l]
                if c3 != 0.0:
                    fu += c3 * work[2 * l, i]
                    fv += c3 * work[2 * l + 1, i]
        su = scheme.atol + scheme.rtol * max(abs(u[i]), abs(u2[i]))
        sv = scheme.atol + scheme.rtol * max(abs(v[i]), abs(v2[i]))
        e5 += (eu / su) ** 2 + (ev / sv) ** 2
        if combined:
            e3 += (fu / su) ** 2 + (fv / sv) ** 2
    m = 2.0 * n1
    if combined:
        den = e5 + 0.01 * e3
        err = dt * e5 / math.sqrt(den * m) if den > 0.0 else 0.0
    else:
        err = dt * math.sqrt(e5 / m)
    if not math.isfinite(err):
        return StepResult(NON_FINITE, err, emin, fl, 0.0, 0.0, 0.0)
    w = momentum(v2, system.h)
    diss *= dt
    fac = _factor(err, q)
    dt_next = dt * fac
    dt_next = _capped(scheme, system, dt_next, om2)
    if err > 1.0:
        return StepResult(INACCURATE, err, emin, fl, dt_next, w, diss)
    return StepResult(OK, 0.0, emin, fl, dt_next, w, diss)


@step_kernel
def _combine(coef, v, a, v2, a2, work, ns, i):
    """Σ_j coef[j] k_j at node i over the stage indices of ``coef`` (the pair's stages, the
    new point ns, the extra stages): its u part (velocities) and v part (accelerations)."""
    su = coef[0] * v[i]
    sv = coef[0] * a[i]
    for j in range(1, coef.size):
        c = coef[j]
        if c != 0.0:
            if j == ns:
                su += c * v2[i]
                sv += c * a2[i]
            else:
                su += c * work[2 * j, i]
                sv += c * work[2 * j + 1, i]
    return su, sv


@step_kernel
def dense_setup(scheme, system, rod, floor, u, v, a, u2, v2, a2, work, dt):
    """Prepare the dense output of the step of length dt from (u, v, a) to (u2, v2, a2)
    that just left its stages in ``work``: evaluate the extra stages (dop853) and store the
    terms R_m.  Returns ``(status, value)``: OK, or the failure code of an extra stage
    outside the admissible set and its offending number."""
    A, _, _, _, _, _ = tableau(scheme)
    AX, D = dense_tableau(scheme)
    ns = A.shape[0]
    n1 = u.size
    us = work[2 * ns]
    for e in range(AX.shape[0]):
        j = ns + 1 + e
        vj = work[2 * j]
        aj = work[2 * j + 1]
        for i in range(n1):
            su, sv = _combine(AX[e], v, a, v2, a2, work, ns, i)
            us[i] = u[i] + dt * su
            vj[i] = v[i] + dt * sv
        status, val, _, _, _ = full_accel(system, rod, floor, us, vj, aj, work[S], work[K],
                                          bool(False))
        if status != OK:
            return status, val
    base = 2 * D.shape[1]
    for m in range(D.shape[0]):
        ru = work[base + 2 * m]
        rv = work[base + 2 * m + 1]
        for i in range(n1):
            su, sv = _combine(D[m], v, a, v2, a2, work, ns, i)
            ru[i] = dt * su
            rv[i] = dt * sv
    return OK, 0.0


@step_kernel
def dense(scheme, u, v, a, u2, v2, a2, work, dt, theta, uo, vo):
    """(u, v) at t + θ dt into ``uo``, ``vo``, from the step's ends and the terms R_m that
    ``dense_setup`` stored (module docstring); reads nothing else, so every output time of
    the step reuses one setup."""
    _, D = dense_tableau(scheme)
    nt = D.shape[0]
    base = 2 * D.shape[1]
    s = theta
    s1 = 1.0 - theta
    for i in range(u.size):
        # R_5 … R_m from the innermost: R_{5+k} is multiplied by θ' for even k, θ for odd k
        tu = 0.0
        tv = 0.0
        for k in range(nt - 1, -1, -1):
            f = s1 if k % 2 == 0 else s
            tu = f * (work[base + 2 * k, i] + tu)
            tv = f * (work[base + 2 * k + 1, i] + tv)
        du = u2[i] - u[i]
        dv = v2[i] - v[i]
        bu = dt * v[i] - du
        bv = dt * a[i] - dv
        cu = du - dt * v2[i] - bu
        cv = dv - dt * a2[i] - bv
        uo[i] = u[i] + s * (du + s1 * (bu + s * (cu + tu)))
        vo[i] = v[i] + s * (dv + s1 * (bv + s * (cv + tv)))


@step_kernel
def dense_dissipated(scheme, system, v, v2, work, dt, theta):
    """The viscous energy dissipated from the step's start to t + θ dt: the continuous
    extension of the step's quadrature Σ b_j 2R(v_j) dt (module docstring); 0 at μ = 0.
    Needs the stages and ``dense_setup``'s extra stages in ``work``."""
    if not system.mu > 0.0:
        return 0.0
    A, B, _, _, _, _ = tableau(scheme)
    _, D = dense_tableau(scheme)
    ns = A.shape[0]
    nt = D.shape[0]
    r0 = _rate(system, v)
    r1 = _rate(system, v2)
    total = 0.0          # Σ b_j r_j
    t5 = 0.0             # Σ d_mj r_j, m = 5 … 8 (DENSE_TERMS_MAX)
    t6 = 0.0
    t7 = 0.0
    t8 = 0.0
    for j in range(D.shape[1]):
        bj = B[j] if j < ns else 0.0
        used = bj != 0.0
        for k in range(nt):
            used = used or D[k, j] != 0.0
        if not used:
            continue
        r = r0 if j == 0 else r1 if j == ns else _rate(system, work[2 * j])
        total += bj * r
        t5 += D[0, j] * r
        if nt > 1:
            t6 += D[1, j] * r
        if nt > 2:
            t7 += D[2, j] * r
        if nt > 3:
            t8 += D[3, j] * r
    s = theta
    s1 = 1.0 - theta
    tail = 0.0
    if nt > 3:
        tail = s * (dt * t8)
    if nt > 2:
        tail = s1 * (dt * t7 + tail)
    if nt > 1:
        tail = s * (dt * t6 + tail)
    tail = s1 * (dt * t5 + tail)
    delta = dt * total
    b0 = dt * r0 - delta
    c0 = delta - dt * r1 - b0
    return s * (delta + s1 * (b0 + s * (c0 + tail)))
