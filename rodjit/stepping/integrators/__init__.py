"""The integrators, one module each (``registry.SCHEMES`` names them): ``kdk`` (``verlet``
and ``semi-implicit``), ``energy``, ``erk`` (``dp54`` and ``dop853``), ``radau`` (``radau5``).

No integrator module imports another: what they share (the rates of the first-order form,
``kernels.rates``; the banded solves, ``kernels.banded``; the step factor and the first step
of the second-order schemes, ``stepping.control``; the viscous and beam sub-steps,
``stepping.viscous`` and ``stepping.beam``) lives below them.  ``erk_tableau`` and
``radau_linear`` are parts of one integrator each (its coefficients, its linear algebra).
"""
