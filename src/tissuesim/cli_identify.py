"""``tissuesim identify SCENE --out DIR``: fit the parameters a scene's ``[identify]`` table
names to its measured data (``identification/scene.py``, ``identification/fit.py``)."""

from __future__ import annotations

import csv
import json

__all__ = ["add_identify_parser", "identify_command"]


def add_identify_parser(sub, common) -> None:
    p = sub.add_parser(
        "identify",
        parents=common,
        help="fit a scene's parameters to measured forces and displacements ([identify])",
        description="Fit the parameters the scene's [identify] table names to its measured "
        "data by least squares, with the run's derivatives (docs/guide/identify.md); writes "
        "identify.json and fit.csv to --out and prints the report as JSON.",
    )
    p.add_argument("scene", help="a scene file (TOML) with an [identify] table")
    p.add_argument("--out", required=True, help="directory for identify.json and fit.csv")


def identify_command(args) -> int:
    """Read the scene, fit, write identify.json and fit.csv together (both or neither), print
    the report."""
    import numpy as np

    from tissuesim.identification.fit import identify
    from tissuesim.identification.scene import read_identify_scene
    from tissuesim.io.atomic import atomic_outputs
    from tissuesim.io.manifest import prepare_directory

    spec = read_identify_scene(args.scene)
    out = prepare_directory(args.out)
    fit = identify(spec["build"], spec["initial"], spec["observations"], spec["data"],
                   spec["steps"], bounds=spec["bounds"], max_runs=spec["max_runs"])  # fmt: skip
    report = {
        "scene": str(args.scene),
        "parameters": fit.parameters,
        "std": fit.std,
        "rms": fit.rms,
        "runs": fit.runs,
        "success": fit.success,
        "message": fit.message,
    }
    m = fit.values.shape[1]
    header = ["step"] + [f"measured_{j}" for j in range(m)] + [f"simulated_{j}" for j in range(m)]
    measured = np.asarray(spec["data"], dtype=float)
    targets = [out / "identify.json", out / "fit.csv"]
    with atomic_outputs(targets) as (json_tmp, csv_tmp):
        json_tmp.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        with open(csv_tmp, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(header)
            for n, row in enumerate(fit.values):
                w.writerow([n + 1, *("" if np.isnan(v) else repr(float(v)) for v in measured[n]),
                            *(repr(float(v)) for v in row)])  # fmt: skip
    print(json.dumps({**report, "written": [str(t) for t in targets]}, indent=2))
    return 0
