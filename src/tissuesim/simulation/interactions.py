"""The calls of ``Simulation`` that make bodies interact (a mixin): contact (IPC's barrier,
``contact/model.py``) and its modes, kinematic obstacles and driving them live, attachments
between two bodies (``coupling/tie.py``, ``coupling/frame_attachment.py``); and the contact
model built over the bodies' surfaces when the system is built."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tissuesim.errors import InputError
from tissuesim.mesh.mesh import Mesh
from tissuesim.validate import short, vector

__all__ = ["InteractionCalls", "CONTACT_MODES"]

#: ``set_contact(mode=...)`` and scene ``[contact] mode`` (``time/contact_step.py``)
CONTACT_MODES = ("auto", "accurate", "interactive", "barrier")


class InteractionCalls:
    """Mixed into ``Simulation``."""

    # -- contact ------------------------------------------------------------------------------
    def set_contact(
        self,
        enabled: bool = True,
        *,
        dhat: float | None = None,
        stiffness: float | str | None = None,
        friction: float = 0.0,
        eps_v: float = 1e-3,
        friction_iterations: int = 2,
        surfaces: dict | None = None,
        pairs: Sequence | None = None,
        mode: str = "auto",
    ) -> None:
        """Barrier contact (IPC) between every FEM body's surface, itself and the obstacles
        (``contact/model.py``): ``dhat`` the activation distance (m; default 1e-3 of the
        scene's size), ``stiffness`` the barrier's kappa (Pa, fixed; default None or
        "adaptive": IPC's adaptive kappa from the largest Young's modulus E, within
        [E, 100 E], contact/barrier/stiffness.py);
        ``friction`` the Coulomb coefficient mu (IPC's smoothed friction, static
        below the sliding speed ``eps_v`` m/s, lagged over ``friction_iterations`` Newton
        solves per step). ``surfaces`` maps a body name to its contact surface, a facet set
        name (e.g. "zmax") or (k, 3) vertex indices (default: its whole boundary; leave out
        symmetry planes and faces that cannot touch). ``pairs``: ``ContactPair(a, b,
        enabled=, friction=)`` or ``{"bodies": [a, b], "enabled": ..., "friction": ...}``
        per pair of bodies / a body and an obstacle / a body with itself (a == b).
        ``mode`` (``time/contact_step.py``): "accurate" (the step's contacts predicted on the
        compliance, then the barrier's Newton from there: the barrier's answer and guarantee),
        "interactive" (the prediction, certified free of intersection by CCD, is the step;
        forces are its multipliers), "barrier" (the barrier's Newton alone), "auto" (the
        default: the barrier, interactive for steps with a budget). Contact needs no extra:
        the IPC Toolkit (ipctk) is installed with tissuesim."""
        import importlib.util

        from tissuesim.contact.model import ContactSettings
        from tissuesim.validate import real

        if enabled and importlib.util.find_spec("ipctk") is None:
            # ipctk is a dependency of tissuesim: missing only if it was uninstalled
            raise InputError(
                "contact needs the IPC Toolkit (ipctk, a dependency of tissuesim that is "
                "missing here): pip install ipctk"
            )
        if self.explicit and enabled:
            raise InputError("contact needs an implicit integrator (backward_euler, quasistatic)")
        if dhat is not None:
            dhat = real(dhat, "contact dhat", low=0.0, low_open=True, unit="m")
        if stiffness is not None and stiffness != "adaptive":
            if isinstance(stiffness, str):
                raise InputError(
                    f'contact stiffness must be a number (Pa) or "adaptive", not {stiffness!r}'
                )
            stiffness = real(stiffness, "contact stiffness", low=0.0, low_open=True, unit="Pa")
        from tissuesim.validate import integer

        friction = real(friction, "contact friction", low=0.0)
        eps_v = real(eps_v, "contact eps_v", low=0.0, low_open=True, unit="m/s")
        iterations = integer(friction_iterations, "contact friction_iterations", low=1, high=20)
        from tissuesim.validate import choice

        mode = choice(mode, "contact mode", CONTACT_MODES)
        settings = ContactSettings(
            dhat, stiffness, friction, eps_v, iterations, _surfaces(surfaces), _pairs(pairs), mode
        )
        self.contact = settings if enabled else None
        self._changed()

    def add_obstacle(
        self, name: str, surface, *, translation=None, rotation=None, friction=None
    ) -> str:
        """A kinematic rigid obstacle (``contact/obstacles.py``): a triangle ``surface``
        (``tissuesim.plane`` / ``sphere`` / ``capsule`` / ``cylinder``, ``read_surface``,
        ``frames.sampling.box_surface``) moved by ``translation`` (m) and ``rotation`` (a
        rotation vector about its centroid, rad), each a function of t or three numbers (a
        fixed offset from where the surface was made), with its own Coulomb ``friction``
        against every body (default the scene's). Its force on the bodies is reported as
        ``name`` (and its normal and friction parts as ``name.normal``, ``name.friction``).
        Switches contact on (``set_contact``) if it is off."""
        from tissuesim.contact.obstacles import Obstacle
        from tissuesim.frames.sampling import Surface

        if not isinstance(surface, Surface):
            raise InputError(
                f"add_obstacle: surface must be a Surface, not {type(surface).__name__}"
            )
        # a fixed place as numbers (a 3-vector, as a scene's constant expressions give) or a
        # function of t
        translation = _motion(translation, "translation", "m")
        rotation = _motion(rotation, "rotation", "rad")
        # a file stem clashing with no body, obstacle or internal series; then its force name
        if friction is not None:
            from tissuesim.validate import real

            friction = real(friction, f"obstacle {name!r} friction", low=0.0)
        name = self._claim_force_name(self._new_name(name, "obstacle"))
        self.obstacles.append(Obstacle(name, surface, translation, rotation, friction))
        if getattr(self, "contact", None) is None:
            self.set_contact()
        self._changed()
        return name

    def drive_obstacle(
        self, name: str, translation: Sequence[float] | None = None, rotation=None
    ) -> None:
        """Drive obstacle ``name`` live: its ``translation`` (m, from its rest place) and / or
        ``rotation`` (a rotation vector about its rest centroid, rad) at the end of the next
        step, reached on a straight line from where it is now. Call it between steps (from a
        haptic device, the mouse, a script); the next ``step()`` returns the obstacle's force
        in ``extra["forces"][name]``. The first call replaces the motion given to
        ``add_obstacle`` by a live one (contact/obstacles.py DrivenMotion)."""
        from dataclasses import replace

        from tissuesim.contact.obstacles import DrivenMotion

        names = [ob.name for ob in self.obstacles]
        if name not in names:
            known = ", ".join(names) or "none"
            raise InputError(f"drive_obstacle: no obstacle {name!r} (obstacles: {known})")
        k = names.index(name)
        ob = self.obstacles[k]
        t0, t1 = self.time, self.time + self.time_step
        changes = {}
        for key, value in (("translation", translation), ("rotation", rotation)):
            if value is None:
                continue
            motion = getattr(ob, key)
            if not isinstance(motion, DrivenMotion):
                now = np.zeros(3) if motion is None else np.asarray(motion(t0), dtype=float)
                motion = DrivenMotion(now)
                changes[key] = motion
            motion.set(value, t0, t1)
        if changes:
            ob = replace(ob, **changes)
            self.obstacles[k] = ob
            contact = None if self._system is None else self._system.contact
            if contact is not None:  # the built model keeps its mesh; only the motion changes
                contact.obstacles[k] = ob

    # -- attachments between two bodies -------------------------------------------------------
    def attach(
        self,
        body: str,
        to: str,
        *,
        distance: float | None = None,
        stiffness: float | None = None,
        name: str | None = None,
    ):
        """Glue ``body`` to ``to`` where they touch, by a stiff penalty; the force ``to`` exerts
        on ``body`` is reported as ``name`` (default "<body>-<to>").

        Two FEM bodies (``coupling/tie.py``): ``body``'s boundary triangles whose vertices all
        lie within ``distance`` m of ``to`` (default 1e-3 of ``body``'s size); ``stiffness``
        N/m per m^2 of contact (default 250 times the stiffer shear modulus per median edge).
        A frame body and a FEM body (``coupling/frame_attachment.py``): the FEM body's
        boundary triangles facing the frame body's integration points within ``distance``
        (default 1.5 sample spacings); ``stiffness`` default 250 times the frame body's shear
        modulus per spacing (the tissue's rule)."""
        from tissuesim.coupling.tie import tie_bodies
        from tissuesim.coupling.tissue import ATTACHMENT_FACTOR

        a, b = self.body(body, ("fem", "frames")), self.body(to, ("fem", "frames"))
        if a is b:
            raise InputError(f"attach: a body cannot be attached to itself ({body!r})")
        if distance is not None and not (np.isfinite(distance) and distance > 0):
            raise InputError(f"attach: distance must be > 0 m, got {short(distance)}")
        if stiffness is not None and not (np.isfinite(stiffness) and stiffness > 0):
            raise InputError(f"attach: stiffness must be > 0 N/m per m^2, got {short(stiffness)}")
        if a.kind == b.kind == "frames":
            raise InputError(
                f"attach: {body!r} and {to!r} are both frame bodies; attach a frame body to a "
                "FEM body, or make them one frame body"
            )
        if "frames" in (a.kind, b.kind):
            return self._attach_frames(a, b, distance, stiffness, name)
        size = float(np.linalg.norm(np.ptp(a.mesh.points, axis=0)))
        if distance is None:
            distance = 1e-3 * size
        name = self._claim_force_name(name, f"{body}-{to}")
        edge = _median_boundary_edge(a.mesh)
        if stiffness is None:
            mu = max(a.model.material.mu, b.model.material.mu)
            stiffness = ATTACHMENT_FACTOR * mu / edge
        tie = tie_bodies(
            name, a.name, a.mesh, b.name, b.mesh, distance=distance, stiffness_per_area=stiffness
        )
        self.ties.append(tie)
        self._changed()
        return tie

    def _attach_frames(self, a, b, distance, stiffness, name):
        from tissuesim.coupling.frame_attachment import frame_attachment
        from tissuesim.coupling.tissue import ATTACHMENT_FACTOR

        frame, fem = (a, b) if a.kind == "frames" else (b, a)
        samples = frame.model.samples
        spacing = float(np.cbrt(np.median(samples.volumes)))
        distance = 1.5 * spacing if distance is None else float(distance)
        if stiffness is None:
            stiffness = ATTACHMENT_FACTOR * frame.model.material.mu / spacing
        name = self._claim_force_name(name, f"{a.name}-{b.name}")
        spec = frame_attachment(
            name,
            fem.name,
            fem.mesh,
            frame.name,
            samples,
            distance=distance,
            stiffness_per_area=stiffness,
        )
        spec.build(0, 1, frame.model)  # points the frames do not reach fail now
        spec_sign = 1.0 if a is fem else -1.0  # the force is reported on ``body``
        self.frame_attachments.append((spec, spec_sign))
        self._changed()
        return spec

    # -- the contact model, built with the system ---------------------------------------------
    def _contact_model(self):
        """The contact model over every FEM body's surface and every frame body's embedded
        surface (a frame body without one, and the tissue, take no part)."""
        from tissuesim.contact.geometry.surfaces import fem_surface, frame_surface
        from tissuesim.contact.model import ContactModel
        from tissuesim.io.third_party_logs import quiet_ipctk

        quiet_ipctk()  # before contact's first ipctk call: its warnings stay off stderr
        s, settings = self._system, self.contact
        surfaces = []
        dhat = self._contact_dhat()
        for j, name in enumerate(s.names):
            body, choice = self.bodies[name], settings.surfaces.get(name)
            config, tangent = s.config_slices[j], s.tangent_slices[j]
            if body.kind == "fem":
                blade = self._blade_in(name)
                surfaces.append(
                    fem_surface(name, s.bodies[j], config.start, tangent.start, choice, dhat, blade)
                )
            elif body.kind == "frames" and body.surface is not None:
                embedding = body.embedded["surface"]
                surfaces.append(
                    frame_surface(
                        name,
                        s.bodies[j],
                        embedding,
                        body.surface.triangles,
                        config,
                        tangent,
                        choice,
                    )
                )
            elif choice is not None:
                raise InputError(
                    f"contact surfaces: body {name!r} has no contact surface (a frame body "
                    "needs an embedded surface, embed_surface; the tissue takes no part)"
                )
        named = {sf.name for sf in surfaces}
        unknown = set(settings.surfaces) - set(s.names)
        if unknown:
            raise InputError(
                f"contact surfaces: no body {sorted(unknown)[0]!r} (bodies in contact: "
                f"{', '.join(sorted(named))})"
            )
        if not surfaces:
            raise InputError(
                "contact acts on FEM bodies and frame bodies with an embedded surface; this "
                "simulation has none"
            )
        model = ContactModel(surfaces, list(self.obstacles), _with_blades(self), s.n_dofs)
        if any(self._cuts_ahead(c) for c in self.organ_cuts):
            model.clear_path = self._clear_blade_paths
        return model

    def _contact_dhat(self) -> float:
        """The barrier's dhat (m) as the contact model will take it: the scene's, else 1e-3 of
        the diagonal of the bodies' and obstacles' bounding box."""
        if self.contact.dhat is not None:
            return float(self.contact.dhat)
        pts = [b.mesh.points for b in self._active() if b.kind == "fem" and b.mesh.dim == 3]
        pts += [ob.rest for ob in self.obstacles]
        if not pts:
            return 0.0
        P = np.vstack(pts)
        return 1e-3 * float(np.linalg.norm(np.ptp(P, axis=0)))


def _median_boundary_edge(mesh: Mesh) -> float:
    from tissuesim.mesh.queries.boundary import boundary_facets

    P = mesh.points[boundary_facets(mesh.simplices)]
    return float(np.median(np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2)))


def _surfaces(surfaces) -> dict:
    if surfaces is None:
        return {}
    if not isinstance(surfaces, dict) or not all(isinstance(k, str) for k in surfaces):
        raise InputError(
            "contact surfaces: give a table of body name -> facet set name (or vertex "
            f"triangles), e.g. {{'block': 'zmax'}}, not {short(surfaces)}"
        )
    return dict(surfaces)


def _pairs(pairs) -> tuple:
    from tissuesim.contact.pairs import ContactPair

    if pairs is None:
        return ()
    if isinstance(pairs, (str, dict)) or not isinstance(pairs, Sequence):
        raise InputError(f"contact pairs: give a list of pairs, not {short(pairs)}")
    out = []
    for item in pairs:
        if isinstance(item, ContactPair):
            out.append(item)
            continue
        if not isinstance(item, dict) or set(item) - {"bodies", "enabled", "friction"}:
            raise InputError(
                "contact pairs: each is ContactPair(a, b, ...) or a table with keys bodies, "
                f"enabled, friction, not {short(item)}"
            )
        names = item.get("bodies")
        if not isinstance(names, (list, tuple)) or len(names) != 2:
            raise InputError(
                f"contact pairs: bodies must name two bodies (or a body twice, for its self "
                f"contact, or a body and an obstacle), not {short(names)}"
            )
        out.append(ContactPair(names[0], names[1], item.get("enabled", True), item.get("friction")))
    return tuple(out)


class _Fixed:
    """A motion that stays put: the numbers ``add_obstacle`` was given, at every t (a class,
    not a lambda, so that an obstacle pickles)."""

    def __init__(self, value: np.ndarray) -> None:
        self.value = value

    def __call__(self, t: float) -> np.ndarray:
        return self.value.copy()


def _motion(value, what: str, unit: str):
    """``add_obstacle``'s translation / rotation: None, a function of t, or three numbers."""
    if value is None or callable(value):
        return value
    if isinstance(value, str) or not hasattr(value, "__len__"):
        raise InputError(
            f"add_obstacle: {what} must be a function of t, three numbers ({unit}) or None, "
            f"not {short(value)}"
        )
    return _Fixed(vector(value, f"add_obstacle {what}", 3, unit=unit))


def _with_blades(sim) -> object:
    """The contact settings with each obstacle that cuts a body without contact out of contact
    with that body (it passes through what it cuts), unless the scene pairs them itself."""
    from dataclasses import replace

    from tissuesim.contact.pairs import ContactPair

    settings = sim.contact
    listed = {frozenset((p.a, p.b)) for p in settings.pairs}
    blades = [
        ContactPair(c.body, c.obstacle, enabled=False)
        for c in sim.organ_cuts
        if c.obstacle is not None
        and (not c.contact or c.suspended)
        and frozenset((c.body, c.obstacle)) not in listed
    ]
    return replace(settings, pairs=tuple(settings.pairs) + tuple(blades)) if blades else settings
