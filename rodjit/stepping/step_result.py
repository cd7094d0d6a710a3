"""What a scheme's ``initial`` and ``step`` return to the loop."""
from typing import NamedTuple


class StepResult(NamedTuple):
    """The outcome of a trial step (or of the initial state's evaluation).

    ``status``: OK, a failure code of ``kernels.forces`` (the loop retries a shorter step),
    or INACCURATE (a valid state whose error estimate is too large: the loop retries with
    ``dt_suggest``).  ``value``: the offending number of a failure (strain, height, error
    ratio, Newton update).  ``min_strain``, ``floor_force``: of the new state.
    ``dt_suggest``: the scheme's next step, cfl × its stability limit (explicit schemes) or
    from its error ratio (``energy``).  ``w``: the new state's centre-of-mass velocity
    Σ m v; ``dissipated``: the viscous energy the step removed (both 0 for ``initial``).
    """

    status: int
    value: float
    min_strain: float
    floor_force: float
    dt_suggest: float
    w: float
    dissipated: float
