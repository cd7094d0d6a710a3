"""The public way to write a stress law: ``rodjit.laws``."""
import math

import numpy as np
import pytest

import rodjit
import rodjit.laws as laws
from rodjit import _jit


def test_the_public_names():
    assert laws.law_kernel is _jit.kernel
    assert laws.Law is rodjit.model.laws.Law and laws.register is rodjit.model.laws.register
    for name in laws.__all__:
        assert hasattr(laws, name), name


@pytest.mark.slow
def test_the_documented_example_registers_and_runs(tmp_path, monkeypatch):
    """The example in the module's docstring, as a user's module of its own."""
    doc = laws.__doc__
    code = doc[doc.index("    import math"):doc.index("``Law`` documents")]
    (tmp_path / "doc_law.py").write_text("\n".join(line[4:] for line in code.splitlines()))
    monkeypatch.syspath_prepend(str(tmp_path))
    import doc_law
    law = laws.get_law("rod", "ln")
    assert law.params is doc_law.LnRod
    p = doc_law.LnRod(100.0)
    assert laws.value(0.5, p) == 100.0 * math.log1p(0.5) and laws.lower(p) == -1.0
    e = np.linspace(-0.9, 2.0, 9)      # the primitive's derivative is the stress
    dp = [(laws.primitive(x + 1e-6, p) - laws.primitive(x - 1e-6, p)) / 2e-6 for x in e]
    np.testing.assert_allclose(dp, [laws.value(x, p) for x in e], rtol=1e-6)
    res = rodjit.simulate(rodjit.Config().override({"rod.law": "ln", "rod.N": 4,
                                                     "time.t_end": 0.05}))
    e = res.diagnostics["energy_total"]
    assert np.all(np.isfinite(e)) and abs(e[-1] - e[0]) < 1e-3 * abs(e[0])
