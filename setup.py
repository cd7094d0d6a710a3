"""The ahead-of-time compiled loops of the integrators the default run chooses from
(``aot.schemes``: the registry's ``Scheme.aot`` rows) and the sweeps' batch kernel for their
types (``rodjit.stepping.aot``), built at install.  Everything else about the package is in
pyproject.toml.

``build_ext`` compiles the extension ``rodjit.stepping._aot_loop`` in a separate
interpreter that imports only the modules it needs (not ``rodjit/__init__``, which would
need every runtime dependency in the build environment), with a throw-away Numba cache.
It is optional: if the compile fails (no C compiler, say), the install goes on and runs
use the JIT.  An extension already in the source tree that was built from the same
sources for this host (an earlier editable install of this checkout) is kept instead of
compiled again (``aot.reusable``): a second ``pip install -e ".[extra]"`` took 49 s with
the compile of one integrator's loop (two take 73–107 s to compile, ``stepping.aot``) and
2.5 s without (2 cores, no build isolation).
"""
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent

_BUILD = """
import sys, types
root, out = sys.argv[1], sys.argv[2]
package = types.ModuleType("rodjit")
package.__path__ = [root]
sys.modules["rodjit"] = package
from rodjit.config import Config
from rodjit.driver.setup import parameters
from rodjit.stepping import aot
print(aot.build(out, [parameters(Config().override({"time.integrator": name}))
                      for name in aot.schemes()]))
"""


RECORD = "_aot_loop.json"      # the extension's record (``stepping.aot``), beside it

_REUSABLE = """
import sys, types
root, directory = sys.argv[1], sys.argv[2]
package = types.ModuleType("rodjit")
package.__path__ = [root]
sys.modules["rodjit"] = package
from rodjit.stepping import aot
print(aot.reusable(directory) or "")
"""


class BuildAot(build_ext):
    """Builds the extension with ``numba.pycc`` instead of a C compiler's sources, and
    installs its record with it (an editable install copies both into the source tree)."""

    def copy_extensions_to_source(self):
        super().copy_extensions_to_source()
        for regular, inplace in self._records():
            if os.path.exists(regular):
                self.copy_file(regular, inplace, level=self.verbose)

    def get_output_mapping(self):
        return {**super().get_output_mapping(), **{i: r for r, i in self._records()
                                                   if self.inplace}}

    def get_outputs(self):
        outputs = super().get_outputs()
        if not self.inplace:
            outputs += [r for r, _ in self._records()]
        return outputs

    def _records(self):
        """``(build, in-place)`` paths of each extension's record."""
        build_py = self.get_finalized_command("build_py")
        for ext in self.extensions:
            inplace, regular = self._get_inplace_equivalent(build_py, ext)
            yield (os.path.join(os.path.dirname(regular), RECORD),
                   os.path.join(os.path.dirname(inplace), RECORD))

    def build_extension(self, ext):
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        if self._keep_built(ext, target):
            return
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache, "RODJIT_AOT": "0"}
            proc = subprocess.run([sys.executable, "-c", _BUILD, str(ROOT / "rodjit"),
                                   str(target.parent)], env=env, capture_output=True,
                                  text=True)
        if proc.returncode != 0 or not target.exists():
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-3:]
            print("rodjit: the ahead-of-time loop was not built; runs will compile it on "
                  "first use (" + " / ".join(tail) + ")", file=sys.stderr)


    def _keep_built(self, ext, target: Path) -> bool:
        """Copy the extension already in the source tree to ``target`` (with its record)
        where it was built from these sources for this host (``aot.reusable``): one
        compile per install of a checkout, not one per ``pip install -e ".[extra]"``."""
        inplace, _ = self._get_inplace_equivalent(self.get_finalized_command("build_py"),
                                                  ext)
        source_dir = Path(inplace).parent
        env = {**os.environ, "RODJIT_AOT": "0"}
        proc = subprocess.run([sys.executable, "-c", _REUSABLE, str(ROOT / "rodjit"),
                               str(source_dir)], env=env, capture_output=True, text=True)
        found = proc.stdout.strip() if proc.returncode == 0 else ""
        if not found:
            return False
        if Path(found).resolve() != target.resolve():
            shutil.copy2(found, target)
            shutil.copy2(source_dir / RECORD, target.parent / RECORD)
        print("rodjit: the ahead-of-time loop built for these sources is kept (no compile)",
              file=sys.stderr)
        return True


setup(ext_modules=[Extension("rodjit.stepping._aot_loop", sources=[], optional=True)],
      cmdclass={"build_ext": BuildAot})
