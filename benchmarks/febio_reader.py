"""Reading FEBio models grows linearly with their size: ``tissuesim convert`` (read the .feb,
write the scene and its Gmsh mesh) on hex8 block models of 1e5 to 1e6 nodes, and on a model
whose 200k-id node set is written one id per line (every id its own text chunk for the XML
parser). The reader appended every text chunk to a string (O(size^2): 100k nodes took 3.5 s,
200k 36 s, 400k 249 s, issue 41); it now joins them once per element.

Each size runs in its own process (a clean peak memory), once: timings on a shared machine are
noisy, so read the table for its growth, not its last digit.

    python benchmarks/febio_reader.py                 # 1e5, 2e5, 4e5, 1e6 nodes + the 200k set
    python benchmarks/febio_reader.py --sizes 20000   # a quick look
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SIZES = (100_000, 200_000, 400_000, 1_000_000)
SET_IDS = 200_000


def write_model(path: Path, n_nodes: int, one_id_per_line: bool = False) -> int:
    """A FEBio 4.0 hex8 block of about ``n_nodes`` nodes (k x k x m), its bottom fixed, its
    top pulled along a load curve; with ``one_id_per_line`` the bottom set is every node, one
    id per line. Returns the number of nodes written."""
    k = max(2, round((n_nodes / 4) ** (1 / 3)))
    m = max(2, round(n_nodes / (k * k)))
    nx = ny = k
    nz = m
    nid = lambda i, j, q: 1 + i + nx * (j + ny * q)  # noqa: E731
    with open(path, "w", encoding="utf-8") as f:
        w = f.write
        w('<?xml version="1.0" encoding="ISO-8859-1"?>\n<febio_spec version="4.0">\n')
        w('  <Module type="solid"/>\n  <Control>\n    <analysis>STATIC</analysis>\n')
        w("    <time_steps>2</time_steps>\n    <step_size>0.5</step_size>\n  </Control>\n")
        w('  <Material>\n    <material id="1" name="tissue" type="neo-Hookean">\n')
        w("      <density>1000</density>\n      <E>10000</E>\n      <v>0.3</v>\n")
        w('    </material>\n  </Material>\n  <Mesh>\n    <Nodes name="block">\n')
        h = 1.0 / (k - 1)
        for q in range(nz):
            for j in range(ny):
                for i in range(nx):
                    xyz = f"{i * h:.6g},{j * h:.6g},{q * h:.6g}"
                    w(f'      <node id="{nid(i, j, q)}">{xyz}</node>\n')
        w('    </Nodes>\n    <Elements type="hex8" name="block">\n')
        e = 1
        for q in range(nz - 1):
            for j in range(ny - 1):
                for i in range(nx - 1):
                    c = [nid(i, j, q), nid(i + 1, j, q), nid(i + 1, j + 1, q), nid(i, j + 1, q)]
                    c += [
                        nid(a, b, q + 1)
                        for a, b in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1))
                    ]
                    w(f'      <elem id="{e}">{",".join(map(str, c))}</elem>\n')
                    e += 1
        w("    </Elements>\n")
        total = nx * ny * nz
        bottom = [nid(i, j, 0) for j in range(ny) for i in range(nx)]
        top = [nid(i, j, nz - 1) for j in range(ny) for i in range(nx)]
        if one_id_per_line:
            w('    <NodeSet name="bottom">\n')
            w("".join(f"{i},\n" for i in range(1, total + 1)))
            w("    </NodeSet>\n")
        else:
            w(f'    <NodeSet name="bottom">{",".join(map(str, bottom))}</NodeSet>\n')
        w(f'    <NodeSet name="top">{",".join(map(str, top))}</NodeSet>\n')
        w('  </Mesh>\n  <MeshDomains>\n    <SolidDomain name="block" mat="tissue"/>\n')
        w("  </MeshDomains>\n  <Boundary>\n")
        w('    <bc name="base" node_set="bottom" type="zero displacement">\n')
        w("      <x_dof>1</x_dof>\n      <y_dof>1</y_dof>\n      <z_dof>1</z_dof>\n    </bc>\n")
        if not one_id_per_line:
            w('    <bc name="pull" node_set="top" type="prescribed displacement">\n')
            w('      <dof>z</dof>\n      <value lc="1">0.01</value>\n')
            w("      <relative>0</relative>\n")
            w("    </bc>\n")
        w("  </Boundary>\n  <LoadData>\n")
        w('    <load_controller id="1" name="ramp" type="loadcurve">\n      <points>\n')
        w("        <pt>0,0</pt>\n        <pt>1,1</pt>\n      </points>\n    </load_controller>\n")
        w("  </LoadData>\n</febio_spec>\n")
    return total


def child(path: str) -> None:
    """Convert ``path`` in this process and print the times and peak memory as JSON."""
    start = time.perf_counter()
    from tissuesim.febio import convert_febio, read_feb

    imported = time.perf_counter()
    read_feb(path)
    read = time.perf_counter()
    out = Path(path).with_suffix(".scene.toml")
    convert_febio(path, out, force=True)
    done = time.perf_counter()
    peak = 0.0
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            peak = float(line.split()[1]) / 1024
    print(json.dumps({"import_s": imported - start, "read_s": read - imported,
                      "convert_s": done - read, "peak_mib": peak}))  # fmt: skip


def measure(directory: Path, n: int, one_id_per_line: bool) -> dict:
    feb = directory / f"block_{n}{'_set' if one_id_per_line else ''}.feb"
    made = time.perf_counter()
    nodes = write_model(feb, n, one_id_per_line)
    made = time.perf_counter() - made
    result = subprocess.run(
        [sys.executable, __file__, "--child", str(feb)], capture_output=True, text=True, check=True
    )
    row = json.loads(result.stdout.strip().splitlines()[-1])
    row.update(nodes=nodes, size_mib=feb.stat().st_size / 2**20, write_file_s=made,
               case="node set one id per line" if one_id_per_line else "block")  # fmt: skip
    for p in directory.glob(feb.stem + "*"):
        p.unlink()
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=list(SIZES))
    parser.add_argument("--set-ids", type=int, default=SET_IDS, help="0: skip that case")
    parser.add_argument("--out", type=Path, default=None, help="write febio_reader.md there")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cases = [(n, False) for n in args.sizes] + ([(args.set_ids, True)] if args.set_ids else [])
        for n, per_line in cases:
            row = measure(Path(tmp), n, per_line)
            rows.append(row)
            print(json.dumps(row), flush=True)
    lines = [
        "# FEBio reader: convert time against model size",
        "",
        f"`python benchmarks/febio_reader.py` on {platform.node()} ({os.cpu_count()} cores, "
        f"Python {platform.python_version()}), {time.strftime('%Y-%m-%d')}; one run per size, "
        "each in its own process, on a shared machine (timings are noisy).",
        "read: `read_feb` alone; convert: `convert_febio` (read again, then the scene and its "
        "Gmsh mesh written); per 1e5 nodes: read + convert over the size.",
        "",
        "| case | nodes | file (MiB) | read (s) | convert (s) | per 1e5 nodes (s) | peak (MiB) |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in rows:
        per = (r["read_s"] + r["convert_s"]) / r["nodes"] * 1e5
        lines.append(
            f"| {r['case']} | {r['nodes']:,} | {r['size_mib']:.1f} | {r['read_s']:.2f} | "
            f"{r['convert_s']:.2f} | {per:.2f} | {r['peak_mib']:.0f} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "febio_reader.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
