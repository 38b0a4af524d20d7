"""Contact laws: one class per law a case can name (``[contact] law``), registered in
``REGISTRY`` (as the stage types in drystone/model/stages.py). A law says which contact
geometries it runs on and which is its default, how its materials map onto YADE's
``PolyhedraMat`` (drystone/yade_scripts/scene.py builds them), which step engine steps it
(``engine``: a name in drystone/yade_scripts/engines.py) and whether it stores elastic
energy. A new law is one class here and one registration (its engine, if new, one class in
engines.py). No YADE import; SI units (K_n, K_t in N/m^3).
"""
from __future__ import annotations

import math


class ContactLaw:
    """Base of the contact laws; subclasses set the class attributes and ``register``."""

    #: the name a case gives ([contact] law)
    name: str = ""
    #: one line for the case-keys table
    meaning: str = ""
    #: contact geometries it runs on (drystone.mechanics.contact.DETECTIONS), the first its default
    detections: tuple[str, ...] = ()
    #: the step engines it can run with (drystone/yade_scripts/engines.py), the first its default
    engines: tuple[str, ...] = ()

    @property
    def default_detection(self) -> str:
        """The geometry of ``detection = "auto"``."""
        return self.detections[0]

    def engine(self, requested: str, detection: str) -> str:
        """The engine that steps this law on ``detection`` when ``requested`` (``--engine``)."""
        return self.engines[0]

    def yade_material(self, mat: dict, stock_shear_area: float) -> dict:
        """PolyhedraMat parameters (young, poisson, frictionAngle) for material ``mat``
        (density, kn, kt, mu, damping); ``stock_shear_area`` (m^2) from the run spec."""
        raise NotImplementedError


REGISTRY: dict[str, ContactLaw] = {}


def register(cls: type[ContactLaw]) -> type[ContactLaw]:
    """Class decorator: add a contact law to REGISTRY under its ``name``."""
    REGISTRY[cls.name] = cls()
    return cls


def get(name: str) -> ContactLaw:
    """The registered law ``name`` (KeyError naming the known ones)."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise KeyError(f"unknown contact law {name!r}; known: {', '.join(REGISTRY)}") from None


@register
class PenaltyCoulomb(ContactLaw):
    """The Sacsayhuaman paper's law (drystone/mechanics/contact.py): volumetric normal force, per-contact
    incremental shear with Coulomb's cap, damping as a fraction of critical per mode. On the
    native geometry the compiled engine steps it (or, ``--engine python``, the numpy law with
    YADE's integrator, the reference); on YADE's geometry the numpy law."""

    name = "penalty_coulomb"
    meaning = "the paper's law, per-contact shear and damping"
    detections = ("native", "yade")
    engines = ("compiled", "python")
    #: the carried shear force and twisting moment scaled down where the patch shrinks
    #: (drystone.mechanics.contact.carried_share)
    area_scaling = False

    def engine(self, requested, detection):
        return "compiled" if requested == "compiled" and detection == "native" else "python"

    def yade_material(self, mat, stock_shear_area):
        # YADE's volumetric law gives F_n = K_n V with young = 2 K_n (pair stiffness
        # young1 young2 / (young1 + young2)); frictionAngle = 0 makes the stock law zero
        # its shared shear every step (the shear and damping are ours); poisson is unused
        # but must be > 0 (0 gives NaN in Ip2)
        return {"young": 2.0 * mat["kn"], "poisson": 0.5, "frictionAngle": 0.0}


@register
class PenaltyCoulombArea(PenaltyCoulomb):
    """``penalty_coulomb`` with the carried shear force and twisting moment scaled by the
    area (polar moment) ratio where a contact's patch shrinks, kept where it grows, the
    energy the patch lets go either way counted as dissipated (contact.carried_share): the
    stored shear energy cannot grow without work at a joint that opens under shear (a block
    rocking with uplift); barely touching wedge joints, whose area follows their depth,
    couple their normal motion to their shear (docs/energy.md: a settled wall stands still
    all the same). Opt-in, not the default."""

    name = "penalty_coulomb_area"
    meaning = ("the paper's law with the carried shear force scaled down where the contact area shrinks "
               "(no shear energy from nowhere at opening joints: docs/energy.md)")
    area_scaling = True


@register
class StockVolumetric(ContactLaw):
    """YADE's own ``Law2_PolyhedraGeom_PolyhedraPhys_Volumetric`` on its own geometry: the
    normal force as ours, a shear force shared between contacts (it leaks), no damping."""

    name = "stock_volumetric"
    meaning = "YADE's law: shared shear, no damping"
    detections = ("yade",)
    engines = ("yade",)

    def yade_material(self, mat, stock_shear_area):
        # Ip2: ks = (E nu)(E nu)/(E nu + E nu) = E nu / 2 = K_n nu  ->  nu = K_t A_ref / K_n
        return {"young": 2.0 * mat["kn"], "poisson": mat["kt"] * stock_shear_area / mat["kn"],
                "frictionAngle": math.atan(mat["mu"])}


#: the law of a case that names none
DEFAULT = PenaltyCoulomb.name
