"""The rod of MODEL.md §2 in JAX and a diffrax ``jit(vmap)`` solver over it, at a tolerance
matched to rodjit's accuracy: the diffrax peer of bench_gpu.py (on the GPU) and
bench_sweep.py (on the CPU).

The semi-discrete system with γ = 0 and the Aiki–Kosugi laws (MODEL.md §2), written as a
diffrax user would write it, independent of rodjit's kernels.  N, κ and g are fixed by a
base configuration (they set the shapes and the compiled program); μ, κ_b and β are
per-point arguments, so one compiled solver serves a whole grid over them.  The
tolerance is a run-time argument too: choosing it (``matched_tolerance``) compiles once.

tests/test_bench_jax_rod.py checks ``make_rhs`` against rodjit.model.reference.rhs.
jax and diffrax are imported inside the functions: ``missing()`` says, without raising,
whether they are installed.
"""
from __future__ import annotations

import math

import numpy as np

import rodjit
from rodjit.model.system import initial_state

# the tolerances tried for matched accuracy, loosest first (atol = rtol × 1e-3)
TOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TIGHT = {"time.rtol": 1e-11, "time.atol": 1e-14}     # the reference's rodjit tolerances


def missing() -> str | None:
    """Why the diffrax peer cannot run here (jax or diffrax not importable), or None."""
    try:
        import diffrax  # noqa: F401
        import jax  # noqa: F401
    except ImportError as exc:
        return f"jax/diffrax not installed ({exc})"
    return None


def unsupported(config) -> str | None:
    """Why the JAX model cannot represent ``config``'s rod, or None."""
    if config.rod.gamma != 0.0:
        return f"rod.gamma = {config.rod.gamma:g}: the JAX right-hand side has gamma = 0 only"
    if config.rod.law != "aiki-kosugi" or config.floor.law != "aiki-kosugi":
        return "the JAX right-hand side implements the Aiki-Kosugi laws only"
    return None


def make_rhs(config):
    """d/dt [u, v] = rhs(t, y, (μ, κ_b, β)) for ``config``'s N, κ and g (MODEL.md §2, γ = 0,
    Aiki–Kosugi laws), float64."""
    import jax
    import jax.numpy as jnp

    jax.config.update("jax_enable_x64", True)
    reason = unsupported(config)
    if reason:
        raise ValueError(reason)
    n_seg, kappa, g = config.rod.N, config.rod.kappa, config.gravity.g
    h = 1.0 / n_seg
    m = jnp.full(n_seg + 1, h).at[0].set(h / 2).at[-1].set(h / 2)

    def rhs(t, y, args):
        mu, kb, beta = args
        u, v = y[: n_seg + 1], y[n_seg + 1:]
        e = (u[1:] - u[:-1]) / h - 1.0
        q = 1.0 + e
        # f(ε) + μ ε': the segment above node i pulls it up, the one below pulls it down
        seg = 0.5 * kappa * (e + 0.5 - 0.5 / q**3) + mu * (v[1:] - v[:-1]) / h
        f = jnp.zeros(n_seg + 1).at[:-1].add(seg).at[1:].add(-seg) + m * g
        # σ_b(u_0), zero above the floor (the branch's division stays finite there)
        sb = jnp.where(u[0] <= 0.0, kb * (beta**3 / (u[0] + beta) ** 3 - 1.0), 0.0)
        f = f.at[0].add(sb)
        return jnp.concatenate([v, f / m])

    return rhs


def make_solver(config):
    """``solve(mu, kappa_b, beta, tol)``: the final states y(t_end) = [u, v] of diffrax Tsit5
    with a PID controller (rtol = tol, atol = tol × 1e-3) from ``config``'s initial state, one
    row per point, ``jax.jit(jax.vmap(...))`` over the three parameter arrays."""
    import diffrax
    import jax
    import jax.numpy as jnp

    rhs = make_rhs(config)
    u0, v0 = initial_state(config)
    y0 = jnp.concatenate([jnp.asarray(u0), jnp.asarray(v0)])
    t_end = float(config.time.t_end)

    def one(mu, kb, beta, tol):
        sol = diffrax.diffeqsolve(
            diffrax.ODETerm(rhs), diffrax.Tsit5(), t0=0.0, t1=t_end, dt0=1e-5, y0=y0,
            args=(mu, kb, beta), saveat=diffrax.SaveAt(t1=True), max_steps=10_000_000,
            stepsize_controller=diffrax.PIDController(rtol=tol, atol=tol * 1e-3))
        return sol.ys[-1]

    return jax.jit(jax.vmap(one, in_axes=(0, 0, 0, None)))


def point_arrays(configs):
    """μ, κ_b, β of ``configs`` as three float64 arrays (the solver's arguments)."""
    return tuple(np.array([get(c) for c in configs], dtype=np.float64)
                 for get in (lambda c: c.rod.mu, lambda c: c.floor.kappa_b,
                             lambda c: c.floor.beta))


def reference_states(configs):
    """The final heights u(t_end) of ``configs`` by rodjit at tight tolerance (``TIGHT``),
    and rodjit's own final-state error at each config's tolerances: the largest
    |u - u_ref| over the points and nodes."""
    ref, err = [], 0.0
    for c in configs:
        tight = np.asarray(rodjit.simulate(c.override(TIGHT)).u_final)
        own = np.asarray(rodjit.simulate(c).u_final)
        ref.append(tight)
        err = max(err, float(np.max(np.abs(own - tight))))
    return ref, err


def final_state_error(solve, configs, ref, tol) -> float:
    """The largest |u(t_end) - u_ref| of ``solve`` over ``configs`` at ``tol``."""
    n1 = configs[0].rod.N + 1
    ys = np.asarray(solve(*point_arrays(configs), tol))
    return max(float(np.max(np.abs(ys[q, :n1] - r))) for q, r in enumerate(ref))


def matched_tolerance(solve, configs, ref, target_err, tols=TOLS):
    """The loosest of ``tols`` whose final-state error over ``configs`` is at most
    ``target_err`` (rodjit's), with that error; the tightest and its error if none is."""
    tol, err = tols[-1], math.inf
    for tol in tols:
        err = final_state_error(solve, configs, ref, tol)
        if err <= target_err:
            break
    return tol, err
