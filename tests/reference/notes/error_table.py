"""Relative errors of rodjit at defaults vs the semi-discrete reference (JSON)."""
import json, sys, time
sys.path.insert(0, "tests/reference/notes")
REF = json.load(open("tests/reference/reference_values.json"))
from rodjit_first_bounce import run
rows = []
for line in open("tests/reference/notes/defaults.jsonl"):
    rows.append(json.loads(line))
done = {(r["integ"], r["mu"], r["N"]) for r in rows}
for integ, mu, N in [("verlet", 1, 5), ("verlet", 100, 5), ("verlet", 1000, 5), ("verlet", 1, 50), ("verlet", 100, 50), ("verlet", 1, 200)]:
    if (integ, mu, N) not in done:
        r = dict(integ=integ, mu=mu, N=N, **run(integ, mu, N)); rows.append(r)
        with open("tests/reference/notes/defaults.jsonl", "a") as f: f.write(json.dumps(r) + "\n")
print("| integrator | mu | N | steps | restitution | contact time | min u0 | min strain (abs rel) |")
print("|---|---|---|---|---|---|---|---|")
for r in sorted(rows, key=lambda r: (r["integ"], r["N"], r["mu"])):
    key = f"N={r['N']},mu={float(r['mu']):g}"
    if key not in REF["semi_discrete"]: continue
    v = REF["semi_discrete"][key]["values"]
    rel = lambda a, b: abs(a - b) / abs(b)
    print(f"| {r['integ']} | {r['mu']} | {r['N']} | {r['steps']} | {rel(r['e'], v['restitution']):.1e} | {rel(r['tc'], v['contact_time']):.1e} | {rel(r['u0'], v['min_u0']):.1e} | {rel(r['eps'], v['min_strain']):.1e} |")
