"""Joint hardware on generated shapes: 30 seeded drawn shapes (benchmarks/drawn_shapes.py,
seed 11) built without CAD with no switches; per shape its fit, the friction band against its
budget, the free joints and where the tapped chain came to rest.

    OPENBLAS_NUM_THREADS=1 python benchmarks/sweep_hardware.py
"""
import pathlib
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT)); sys.path.insert(0, str(ROOT / "benchmarks"))
from drawn_shapes import design_text, family
from rodcad.design.loader import load_design
from rodcad import pipeline
from rodcad.design.shell import curve_size
for shape in family(30, seed=11):
    p = pathlib.Path(tempfile.mkdtemp())/f"{shape.name}.yaml"; p.write_text(design_text(shape))
    t=time.time()
    try:
        r = pipeline.build(load_design(p), cad=False)
    except Exception as e:
        print(shape.name, "ERROR", type(e).__name__, e); continue
    size=curve_size(r.plan.curve)
    fb = r.as_printed.friction if r.as_printed else None
    hw=r.hardware
    tp=r.tapping
    ok = r.meets_tolerance
    print(f"{shape.name:14s} n={r.n:3d} {'ok ' if ok else 'ex1'} fit {100*r.fit:6.3f}% band {'-' if fb is None else f'{100*fb.band/size:6.3f}%'} budget {'-' if hw is None else f'{100*hw.budget/size:5.3f}%'} "
          f"free {int(np.sum(r.equilibrium.active==0))}/{r.n-1} tap {'-' if tp is None else f'{tp.deviation[-1]:.3f}mm conv={tp.converged}'} {time.time()-t:5.1f}s", flush=True)
