"""A law registered by one process (a user's script) must not break the compiled-code cache
for processes that do not have it."""
import subprocess
import sys
import textwrap


def test_cache_index_with_a_foreign_law_still_loads(tmp_path):
    law = tmp_path / "throwaway_law.py"
    law.write_text(textwrap.dedent('''
        from typing import NamedTuple
        from rodjit._jit import kernel
        from rodjit.model.laws import Law, register

        class Throwaway(NamedTuple):
            kappa: float

        @kernel
        def value(e, p):
            return p.kappa * e / (1.0 + e)

        @kernel
        def deriv(e, p):
            return p.kappa / ((1.0 + e) * (1.0 + e))

        @kernel
        def primitive(e, p):
            return p.kappa * e * e / 2.0   # not the primitive: this law is only typed here

        @kernel
        def lower(p):
            return -1.0

        register(Law("throwaway", "rod", Throwaway, lambda r: Throwaway(float(r.kappa)),
                     value, deriv, primitive, lower))
    '''))
    run = ("import rodjit; rodjit.simulate(rodjit.Config().override("
           "{'rod.law': %r, 'time.t_end': 0.05}))")
    subprocess.run([sys.executable, "-c", "import throwaway_law; " + run % "throwaway"],
                   cwd=tmp_path, check=True, capture_output=True, timeout=600)
    # a process without that module: the cache index names a law it cannot import
    out = subprocess.run([sys.executable, "-c", run % "aiki-kosugi"], cwd="/",
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
