"""``tissuesim mesh SURFACE -o VOLUME``: tetrahedralise a surface
(mesh/from_surface/tetrahedralize.py), its options (size or element count, pytetwild's envelope and
coarsening, smoothing a staircase) and the checks of its output file; ``cli.py`` adds it to the
command line."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

__all__ = ["add_mesh_parser", "mesh_command"]


def add_mesh_parser(sub: argparse._SubParsersAction, common: list) -> None:
    """``tissuesim mesh SURFACE -o VOLUME``: tetrahedralise a surface
    (mesh/from_surface/tetrahedralize.py)."""
    from tissuesim.mesh.from_surface.meshers import MESHERS

    p = sub.add_parser(
        "mesh",
        parents=common,
        help="tetrahedralise a closed surface (STL, OBJ, PLY, ...) into a volume mesh",
        description="Mesh the solid a triangle surface encloses with tetrahedra, check the "
        "result, write it and print a quality summary (JSON). The default mesher, "
        "pytetwild (fTetWild), comes with tissuesim.",
    )
    p.add_argument("surface", help="the surface file, in metres (any format meshio reads)")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="VOLUME",
        help="the volume mesh to write (.vtu, .msh, .xdmf, ...: format from the extension); "
        "written atomically: an existing file is replaced only when meshing succeeds",
    )
    sizing = p.add_mutually_exclusive_group()
    sizing.add_argument(
        "--size",
        type=_length,
        help="target tetrahedron edge length in metres (default 0.05 of the surface's "
        "bounding-box diagonal)",
    )
    sizing.add_argument(
        "--elements",
        type=_count,
        metavar="N",
        help="about N tetrahedra instead of a size: reached within 30 %% (the size estimated "
        "from the volume, then corrected; at most 4 meshing passes)",
    )
    p.add_argument(
        "--mesher",
        choices=("auto", *MESHERS),
        default="auto",
        help="auto (default): pytetwild if installed, else tetgen, else gmsh; pytetwild also "
        "meshes surfaces with holes, flipped triangles or touching parts (docs/meshing.md)",
    )
    envelope = p.add_mutually_exclusive_group()
    envelope.add_argument(
        "--epsilon",
        type=_fraction,
        help="pytetwild: the envelope (how far the mesh's boundary may lie from the surface) "
        "relative to the bounding-box diagonal; fTetWild's -e (default: envelope = size / 20)",
    )
    envelope.add_argument(
        "--envelope",
        type=_length,
        help="pytetwild: the envelope as a width in metres (default: size / 20); wider on a "
        "noisy segmentation, e.g. a voxel",
    )
    p.add_argument(
        "--coarsen",
        action="store_true",
        help="pytetwild: coarsen the mesh as far as its quality allows (fTetWild's --coarsen)",
    )
    p.add_argument(
        "--smoothing",
        choices=("none", "taubin", "sinc"),
        default="none",
        help="smooth a staircase surface (a voxel segmentation) before meshing, keeping its "
        "volume: taubin (NumPy) or sinc (VTK's windowed sinc); default none",
    )
    p.add_argument(
        "--smoothing-iterations",
        type=_count,
        default=None,
        metavar="K",
        help="iterations of the smoothing filter (default 20)",
    )


def mesh_command(args: argparse.Namespace) -> int:
    """``tissuesim mesh``: tetrahedralise, write atomically, print the quality summary."""
    from tissuesim.errors import OutputError
    from tissuesim.io.atomic import atomic_output
    from tissuesim.mesh import write_mesh
    from tissuesim.mesh.from_surface.tetrahedralize import tetrahedralize

    out = Path(args.output)
    if out.is_dir() or not out.parent.is_dir():
        why = "it is a directory" if out.is_dir() else f"no directory {out.parent}"
        raise OutputError(
            f"{out}: cannot write the volume mesh there ({why}); give -o a file path in an "
            "existing directory, e.g. -o organ.vtu"
        )
    _check_volume_format(out)  # before a minute of meshing, not after it
    result = tetrahedralize(args.surface, args.size, mesher=args.mesher, **_mesh_options(args))
    with atomic_output(out) as tmp:
        write_mesh(result.mesh, tmp)
    r = result.report
    keys = ("mesher", "size", "n_tets", "n_points", "min_dihedral_deg", "radius_ratio_min")
    keys += ("volume", "surface_volume", "volume_ratio", "surface", "seconds", "epsilon")
    keys += ("envelope", "coarsen", "smoothing", "target_elements", "passes")
    print(json.dumps({"output": str(out), **{k: r[k] for k in keys}}, indent=2))
    return 0


def _mesh_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of ``tetrahedralize`` that ``tissuesim mesh``'s options give (the
    scene's [mesh] keys of the same names reach the same ones)."""
    options = {
        "target_elements": args.elements,
        "epsilon": args.epsilon,
        "envelope": args.envelope,
        "coarsen": args.coarsen,
        "smoothing": None if args.smoothing == "none" else args.smoothing,
    }
    if args.smoothing_iterations is not None:
        options["smoothing_iterations"] = args.smoothing_iterations
    return options


#: meshio's formats that hold surfaces only: a tetrahedral mesh cannot be written to them
SURFACE_FORMATS = (".stl", ".obj", ".ply", ".off", ".svg", ".wkt")


def _check_volume_format(out: Path) -> None:
    """OutputError (the file, its extension and the formats there are) unless meshio writes
    a volume mesh to ``out``'s extension."""
    import meshio

    from tissuesim.errors import OutputError

    name = out.name.lower()
    known = sorted(meshio.extension_to_filetypes, key=len, reverse=True)
    ext = next((e for e in known if name.endswith(e)), None)
    if ext is None or ext in SURFACE_FORMATS:
        what = f"{out.suffix!r} is not a mesh format" if ext is None else f"{ext} holds surfaces"
        raise OutputError(
            f"{out}: {what}; give -o a volume mesh file: .vtu (VTK), .msh (Gmsh 2.2), .mesh "
            "(medit), .xdmf, ..."
        )


def _length(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 < value < float("inf"):
        raise argparse.ArgumentTypeError(f"must be a length in metres > 0, not {text!r}")
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, not {text!r}")
    return value


def _fraction(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 < value < 0.5:
        raise argparse.ArgumentTypeError(
            f"must be a fraction of the bounding-box diagonal in (0, 0.5), e.g. 0.003, not {text!r}"
        )
    return value
