#!/usr/bin/env python3
"""How the rib cage generator's smooth-union fillet (RibCageParams::blend) changes the Nuss FE
compliance, for the one-surface (labelled) cage and the per-tissue layers joined by tissue_join. One
pectus_nuss_cli run per blend radius and input (default: 6 mm edges, TET10, small strain, Fe = 10 N);
prints faces, tets, sternal elevation and tet volume per tissue.

    python3 bench/cage_fillet.py [--tool build/tools/pectus_nuss_cli] [--blends auto,0,1,3]
                                 [--edge 6] [--quality 1.6] [--force 10]
"""
import argparse
import re
import subprocess

ap = argparse.ArgumentParser()
ap.add_argument("--tool", default="build/tools/pectus_nuss_cli")
ap.add_argument("--blends", default="auto,0,1,3", help="comma-separated radii in mm; 'auto' = the generator's default")
ap.add_argument("--edge", default="6")
ap.add_argument("--quality", default="1.6")
ap.add_argument("--force", default="10")
ap.add_argument("--no-layers", action="store_true", help="only the one-surface cage")
a = ap.parse_args()

print(f"Nuss FE, TET10 small strain, Fe = {a.force} N, {a.edge} mm edges, TetGen quality {a.quality}: fillet radius vs compliance")
print(f"{'input':>12} {'blend mm':>8} {'faces':>6} {'tets':>7} {'elevation mm':>12} {'bone cm3':>9} {'cart. cm3':>9} {'sternum cm3':>11}")
for blend in a.blends.split(","):
    for layers in [False] if a.no_layers else [False, True]:
        cmd = [a.tool, "--edge", a.edge, "--order", "2", "--linear", "--force", a.force, "--quality", a.quality]
        cmd += ([] if blend == "auto" else ["--blend", blend]) + (["--layers"] if layers else [])
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        name = "joined" if layers else "one surface"
        kv = dict(re.findall(r"(\w+)=([-0-9.e]+)", next((l for l in p.stdout.splitlines() if l.startswith("faces=")), "")))
        vol = re.search(r"tet volume mm3: bone ([\d.]+) cartilage ([\d.]+) sternum ([\d.]+)", p.stdout)
        if p.returncode != 0 or "elevation" not in kv or not vol:
            print(f"{name:>12} {blend:>8} failed: {p.stdout.strip()[-200:]}")
            continue
        cm3 = [float(v) / 1000 for v in vol.groups()]
        print(f"{name:>12} {blend:>8} {kv['faces']:>6} {kv['tets']:>7} {float(kv['elevation']):12.2f} "
              f"{cm3[0]:9.2f} {cm3[1]:9.2f} {cm3[2]:11.2f}")
