"""A law registered by one process (a user's script) must not break the compiled-code cache
for processes that do not have it."""
import shutil
import subprocess
import sys
from pathlib import Path


def test_cache_index_with_a_foreign_law_still_loads(tmp_path):
    # the law of tests/custom_law.py, importable only from tmp_path under another name
    shutil.copy(Path(__file__).with_name("custom_law.py"), tmp_path / "throwaway_law.py")
    run = ("import rodjit; rodjit.simulate(rodjit.Config().override("
           "{'rod.law': %r, 'time.t_end': 0.05}))")
    subprocess.run([sys.executable, "-c", "import throwaway_law; " + run % "log-test"],
                   cwd=tmp_path, check=True, capture_output=True, timeout=600)
    # a process without that module: the cache index names a law it cannot import
    out = subprocess.run([sys.executable, "-c", run % "aiki-kosugi"], cwd="/",
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
