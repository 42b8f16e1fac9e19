"""E2E: impossible rib cage parameters are refused with a message naming the parameter and its range,
and no layer is left behind."""
import os

from harness import check, finish, run, workdir
import pectus_mlx as mlx
from pectus_filters import create_ribcage


def script(haller=4.0, edge=6.0, age=7.0):
    return mlx.Script([create_ribcage(age=age, hallerIndex=haller, edgeLength=edge)])

d = workdir("ribcage-bad")
for name, kw in (("hallerIndex", dict(haller=0.5)), ("edgeLength", dict(edge=-1.0)), ("age", dict(age=-2.0))):
    out = os.path.join(d, f"{name}.ply")
    r = run([], script(**kw), [(out, "fc fq", 0)])
    check(r.rc != 0, f"{name}: meshlabserver reports the failure", f"rc {r.rc}")
    msg = [l for l in r.log if f"'{name}'" in l]
    check(bool(msg) and "[" in msg[0], f"{name}: the log names the parameter and its valid range", "\n".join(r.log))
    check(not os.path.exists(out), f"{name}: no rib cage saved")
finish()
