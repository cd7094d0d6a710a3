"""An observer of one's own: the apex of the first rebound, an event that ends the run there.

``output.observer = "rebound-apex"`` (registered by this module) watches every accepted step
for the centre of mass z = h (u_0/2 + u_1 + ... + u_{N-1} + u_N/2) (its height: the rod's
length is 1) and its velocity w, the same average of v.  Once the bottom has touched the floor
and left it again, z flies ballistically (the rod's internal forces cancel in the sum), so
the step in which w turns from rising to falling holds the apex, reached at
t0 + w0/|g| with the height z0 + w0²/(2|g|), exactly.  Its values: ``apex_height`` and
``apex_time`` (NaN without a rebound); with ``Apex.stop`` the run ends at the first step
after the apex (``stop``), so a study of the first bounce costs nothing after it.

Run as a script, it prints ``apex_height`` of the paper's μ = 100 rod from ``simulate``, from
a sweep run inline and from a sweep of two worker processes (``jobs=2``, which import this
module by name: run it from this folder), writes that sweep's file ``apex_sweep.h5`` in the
working directory, and exits non-zero if the three values differ.  From the command line:

    rodjit --import custom_observer run paper-mu100 --set output.observer=rebound-apex
"""
import math
import sys
from typing import NamedTuple

import numpy as np

from rodjit.observers import Observer, observer_kernel, register


class Apex(NamedTuple):
    stop: bool          # end the run once the apex is passed


# the state: what has happened, the apex's height and time, and the previous step's w
PHASE, HEIGHT, TIME = 0, 1, 2     # phase 0: before contact, 1: in contact, 2: rebounding,
SIZE = 3                          # 3: the apex is passed


@observer_kernel
def centre(h, u):
    s = 0.5 * (u[0] + u[u.size - 1])
    for i in range(1, u.size - 1):
        s += u[i]
    return h * s


@observer_kernel
def start(p, st, system, rod, floor, t, u, v):
    st[PHASE] = 1.0 if u[0] < 0.0 else 0.0
    st[HEIGHT] = math.nan
    st[TIME] = math.nan


@observer_kernel
def step(p, st, system, rod, floor, t0, t1, u0, v0, u1, v1):
    phase = st[PHASE]
    if phase == 3.0:
        return
    if u1[0] < 0.0:                       # on the floor: the contact goes on (or starts)
        st[PHASE] = 1.0
        return
    if phase == 1.0:
        st[PHASE] = 2.0                   # it has left the floor: rebounding
        return
    if phase == 2.0:
        w0 = centre(system.h, v0)
        w1 = centre(system.h, v1)
        if w0 > 0.0 and w1 <= 0.0 and system.g < 0.0:
            z0 = centre(system.h, u0)
            st[TIME] = t0 + w0 / -system.g
            st[HEIGHT] = z0 + w0 * w0 / (-2.0 * system.g)
            st[PHASE] = 3.0


@observer_kernel
def stop(p, st):
    return p.stop and st[PHASE] == 3.0


@observer_kernel
def values(p, st, out):
    out[0] = st[HEIGHT]
    out[1] = st[TIME]


OBSERVER = register(Observer(
    name="rebound-apex", params=Apex, size=SIZE,
    columns={"apex_height": "height of the centre of mass at the first rebound's apex [m]",
             "apex_time": "time of that apex [s]"},
    start=start, step=step, stop=stop, values=values,
    from_config=lambda config: Apex(stop=True)))


def main() -> int:
    import rodjit

    cfg = rodjit.load_preset("paper-mu100").override({"output.observer": "rebound-apex",
                                                      "time.t_end": 2.0})
    alone = rodjit.simulate(cfg)
    print(f"simulate: apex_height = {alone.observed['apex_height']!r} m at t = "
          f"{alone.observed['apex_time']!r} s (the run ended at t = {alone.t_final:.6g} s)")
    grid = {"rod.mu": [100.0, 200.0]}
    inline = rodjit.sweep(cfg, grid, scheduler="inline")
    pool = rodjit.sweep(cfg, grid, jobs=2, output="apex_sweep.h5")
    a = float(inline["apex_height"][0])
    b = float(pool["apex_height"][0])
    print(f"inline sweep: {a!r}; 2-job sweep: {b!r} (written to apex_sweep.h5)")
    same = alone.observed["apex_height"] == a == b and np.isfinite(a)
    print("the three agree" if same else "THEY DIFFER")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
