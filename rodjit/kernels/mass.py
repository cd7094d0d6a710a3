"""Node masses of the lumped mass matrix M (MODEL.md §2): h/2 at the ends, h inside."""
from .._jit import step_kernel


@step_kernel
def end_mass(h):
    """m_0 = m_n = h/2: an end node's mass, for code that knows its node is an end (a
    literal index passed to ``node_mass`` would compile it once more)."""
    return 0.5 * h


@step_kernel
def inv_end_mass(ih):
    """1/m_0 from ih = 1/h: 2·(1/h), exactly 1/end_mass."""
    return 2.0 * ih


@step_kernel
def node_mass(i, n, h):
    """m_i of node i of 0..n for the segment length h."""
    return h if 0 < i < n else end_mass(h)


@step_kernel
def inv_node_mass(i, n, ih):
    """1/m_i from ih = 1/h: 2/h at the ends is 2·(1/h) exactly, so this is 1/node_mass bit
    for bit, without a division."""
    return ih if 0 < i < n else inv_end_mass(ih)
