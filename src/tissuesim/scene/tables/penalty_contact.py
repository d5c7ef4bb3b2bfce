"""``[[penalty_contact]]``: FEBio-style penalty / augmented-Lagrangian contact between two FEM
bodies' facet surfaces (``Simulation.add_penalty_contact``, ``contact/penalty/pair.py``);
``convert`` writes one per FEBio sliding contact.

    [[penalty_contact]]
    name = "press"                    # its force on the primary body in forces.csv
    primary = "upper"                 # the body whose facets' points are pressed out
    secondary = "lower"               # the body whose facets they are projected onto
    primary_facets = "zmin"           # facet sets (default: the whole boundary)
    secondary_facets = "zmax"
    penalty = 1e5                     # Pa/m (or auto_penalty = true: E A / V per facet)
    integration = "gauss"             # or "nodes" (FEBio's node-on-facet)
    area = "reference"                # or "current" (FEBio's sliding-elastic)
    two_pass = false
    augmented = false                 # FEBio's augmented Lagrangian:
    tolerance = 0.01                  #   multipliers' norm, relative change
    gap_tolerance = 0.0               #   rms penetration (m)
    min_augmentations = 0
    max_augmentations = 10
    search_tolerance = 0.01           # natural coordinates
    tied = false                      # held where they project at rest (FEBio's tied contacts)
    sticky = false                    # tied where they touch (FEBio's sticky), from within
    snap_tolerance = 0.0              #   this distance (m), letting go above
    max_traction = 0.0                #   this normal traction (Pa; 0: never)
    friction = 0.0                    # Coulomb's coefficient (FEBio's fric_coeff)
    friction_penalty = 0.0            # stick's tangential penalty (Pa/m; 0: penalty's)
    friction_anchor = "step"          # or "contact" (FEBio's node-on-facet)
    keep_last_augmentation = false    # FEBio's sliding-elastic
    special_cases = false             # no facet: onto an interior edge or node (FEBio's
                                      #   node-on-facet, facet-on-facet, tied, sticky)
    tension = false                   # in contact as the surfaces pull apart (FEBio's
                                      #   sliding-elastic tension = 1)
"""

from __future__ import annotations

from tissuesim.errors import SceneError
from tissuesim.scene.common import _context, _table, _unknown

__all__ = ["PENALTY_KEYS", "add_penalty_contacts"]

PENALTY_KEYS = (
    "name", "primary", "secondary", "primary_facets", "secondary_facets", "penalty",
    "auto_penalty", "integration", "area", "two_pass", "augmented", "tolerance",
    "gap_tolerance", "min_augmentations", "max_augmentations", "search_tolerance", "tied",
    "sticky", "snap_tolerance", "max_traction", "friction", "friction_penalty",
    "friction_anchor", "keep_last_augmentation", "special_cases", "tension",
)  # fmt: skip
_FLAGS = ("auto_penalty", "two_pass", "augmented", "tied", "sticky", "keep_last_augmentation",
          "special_cases", "tension")  # fmt: skip
_COUNTS = ("min_augmentations", "max_augmentations")


def add_penalty_contacts(sim, data: dict, source: str) -> None:
    """Read the scene's [[penalty_contact]] into ``sim``."""
    for i, item in enumerate(_table(data, "penalty_contact", source, array=True), start=1):
        where = f"{source} penalty_contact[{i}]"
        _unknown(item, PENALTY_KEYS, where)
        for key in ("primary", "secondary"):
            if not isinstance(item.get(key), str):
                raise SceneError(f"{where}: {key} must be a body's name")
        for key in ("primary_facets", "secondary_facets", "name", "integration", "area",
                    "friction_anchor"):  # fmt: skip
            if key in item and not isinstance(item[key], str):
                raise SceneError(f"{where}: {key} must be a text")
        for key in _FLAGS:
            if key in item and not isinstance(item[key], bool):
                raise SceneError(f"{where}: {key} must be true or false")
        for key in _COUNTS:
            if key in item and (isinstance(item[key], bool) or not isinstance(item[key], int)):
                raise SceneError(f"{where}: {key} must be a whole number")
        options = {k: item[k] for k in PENALTY_KEYS[3:] if k in item}
        with _context(where):
            sim.add_penalty_contact(item["primary"], item["secondary"], name=item.get("name"),
                                    **options)  # fmt: skip
