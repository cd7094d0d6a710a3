"""An observer as a user writes one, for the tests: it counts the accepted steps, keeps the
largest height of the top node and the largest floor stress seen at a step's end (through
the generic ``rodjit.laws.value``, whatever the floor law) and the time of the last step,
and ends the run after ``limit`` steps: ``output.observer = "step-count"`` never,
``"step-count-40"`` after 40 (the same kernels, another parameter class)."""
from typing import NamedTuple

from rodjit.laws import value
from rodjit.observers import Observer, observer_kernel, register


class StepCount(NamedTuple):
    limit: int


class StepCount40(NamedTuple):
    limit: int


@observer_kernel
def start(p, st, system, rod, floor, t, u, v):
    st[1] = u[u.size - 1]
    st[2] = t


@observer_kernel
def step(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1):
    st[0] += 1.0
    st[1] = max(st[1], u1[u1.size - 1])
    st[2] = t1
    st[3] = max(st[3], value(u1[0], floor))


@observer_kernel
def stop(p, st):
    return p.limit > 0 and st[0] >= p.limit


@observer_kernel
def values(p, st, out):
    out[0] = st[0]
    out[1] = st[1]
    out[2] = st[2]
    out[3] = st[3]


COLUMNS = {"observed_steps": "accepted steps seen", "top_max": "largest top height [m]",
           "t_last": "time of the last step [s]",
           "floor_max": "largest floor stress at a step's end [N]"}
OBSERVER = register(Observer(
    name="step-count", params=StepCount, size=4, columns=COLUMNS,
    start=start, step=step, stop=stop, values=values,
    from_config=lambda config: StepCount(0)))
STOPPING = register(Observer(
    name="step-count-40", params=StepCount40, size=4, columns=COLUMNS,
    start=start, step=step, stop=stop, values=values,
    from_config=lambda config: StepCount40(40)))
