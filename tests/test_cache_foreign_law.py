"""Laws registered by other processes (users' scripts) must never break the compiled-code
cache nor be mistaken for one another there."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).parent
RUN = ("import rodjit; r = rodjit.simulate(rodjit.Config().override("
       "{'rod.law': %r, 'time.t_end': 0.05})); print(r.u_final.tolist())")


def python(code, cwd):
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return out.stdout


@pytest.mark.slow   # three fresh processes, each compiling a law's kernels: minutes
def test_foreign_and_same_named_laws_in_the_cache(tmp_path):
    # 1. "log-test" from tests/custom_law.py fills the cache
    first = python("import custom_law; " + RUN % "log-test", HERE)
    # 2. another module registers a law under the same name: its own compiled code is used
    #    (not the cached code of the first, which names a module this process lacks)
    shutil.copy(HERE / "custom_law.py", tmp_path / "throwaway_law.py")
    second = python("import throwaway_law; " + RUN % "log-test", tmp_path)
    assert first == second          # same formulas, so the same numbers
    # 3. a process with neither module: the index names laws it cannot import
    python(RUN % "aiki-kosugi", "/")
