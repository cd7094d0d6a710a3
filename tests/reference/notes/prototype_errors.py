"""Relative first-bounce errors of the stored prototype and fixed-step runs
(prototypes.jsonl, ladder.jsonl) against the semi-discrete reference values."""
import json
from pathlib import Path

HERE = Path(__file__).parent
REF = json.loads((HERE.parent / "reference_values.json").read_text())["semi_discrete"]
for name in ("prototypes.jsonl", "ladder.jsonl"):
    print(name)
    for line in (HERE / name).read_text().splitlines():
        r = json.loads(line)
        if "e" not in r:
            continue
        v = REF.get(f"N={r['N']},mu={float(r['mu']):g}", {}).get("values")
        if v is None:
            continue
        rel = lambda a, b: abs(a - b) / abs(b)
        print(f"  {r.get('scheme', r.get('integ'))} N={r['N']} mu={r['mu']:g} dt={r['dt']:g}: "
              f"e {rel(r['e'], v['restitution']):.2e}  tc {rel(r['tc'], v['contact_time']):.2e}  "
              f"u0 {rel(r['u0'], v['min_u0']):.2e}  eps {r['eps']:.4g} (ref {v['min_strain']:.4g})"
              + (f"  est_u {r['est_u']:.2g} est_v {r['est_v']:.2g}" if r.get("est_u") else ""))
