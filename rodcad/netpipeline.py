"""The pipeline of a net design: a design file with a ``net:`` block in, numbers, report and
pictures out. It sequences the steps and owns none of them::

    design.yaml + catalog -> load_design() (net: rodcad.design.net)   rodcad.design.loader
    -> hardware, lengths, mass bounds, hub masses                      rodcad.design.netplan.plan_net
    -> masses (optimize.design_net), exact equilibrium + multi-start  rodcad.design.netplan.design_net_plan
    -> design.json, report.md, preview.png                            rodcad.outputs.net*

The solids of a net (hubs, rods) are not made yet: ``build`` writes the design only.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rodcad.design.model import Design
from rodcad.design.netplan import NetCheck, design_net_plan, plan_net
from rodcad.outdir import staged_output
from rodcad.outputs.design_json import print_profile, write_json
from rodcad.outputs.netjson import net_json
from rodcad.outputs.netpreview import plot_net
from rodcad.outputs.netreport import net_report
from rodcad.progress import Progress

__all__ = ["NetBuild", "build_net", "write_net_outputs"]


@dataclass
class NetBuild:
    """One run of a net design.

    Attributes:
        design: the validated design.
        check: the designed net, its equilibrium and fit.
        seed: the multi-start's seed.
    """

    design: Design
    check: NetCheck
    seed: int

    @property
    def ok(self) -> bool:
        return self.check.ok

    def limit(self) -> str:
        return self.check.limit()


def build_net(design: Design, *, seed: int | None = None, progress: Progress | None = None) -> NetBuild:
    """Design a net: hardware and rods on the target, masses, the exact equilibrium.

    Raises:
        DesignLimit: rods the catalog cannot print, nodes too crowded for the hubs.
    """
    progress = progress or Progress(quiet=True)
    seed = design.seed if seed is None else int(seed)
    t = design.net
    with progress.step(f"laying hubs and rods on the target ({t.n} nodes, {t.m} rods)"):
        plan = plan_net(t, design.catalog)
    with progress.step("designing the masses and solving the net (exact equilibrium, multi-start)") as st:
        st.note(f"{t.m} rods, mass bounds {plan.bounds[:, 0].min():.3g}-{plan.bounds[:, 1].max():.3g} g")
        check = design_net_plan(plan, g=design.g, seed=seed, tolerance=design.tolerance)
    return NetBuild(design, check, seed)


def write_net_outputs(b: NetBuild, outdir: str | Path, *, progress: Progress | None = None) -> dict[str, Any]:
    """Write design.json, report.md and preview.png to ``outdir`` (staged: a failed run
    leaves it as it was). Returns the data written to design.json."""
    progress = progress or Progress(quiet=True)
    d = b.design
    with staged_output(Path(outdir)) as tmp, progress.step("writing design.json, report.md, preview.png"):
        data = net_json(b.check, name=d.name, seed=b.seed, catalog=d.catalog, print_profile=print_profile(d.catalog))
        write_json(tmp / "design.json", data)
        plot_net(b.check, f"{d.name}: {b.check.error_mm:.3g} mm ({100 * b.check.rel_size:.3g} % of its size) off "
                 "its target", tmp / "preview.png")
        (tmp / "report.md").write_text(net_report(b.check, data, title=d.name), encoding="utf-8")
    return data
