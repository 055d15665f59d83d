"""MJCF export of the stack: the same bodies as the URDF, its loops closed by MuJoCo
equality constraints, one position actuator per leg.

Layout (chosen so that both MuJoCo and Pinocchio's MJCF parser load the same file):

* ``plate_0`` is the only top-level body and has no joint: the base is fixed to the world.
  (Pinocchio's parser reads the first top-level body only, and MuJoCo allows free joints at
  the top level only, so the plates cannot be free bodies.)
* Plate k+1 is nested in plate k at the home offset, with three slides (``sp{k}_plate_x``,
  ``_y``, ``_z``, along plate k's axes) and a ball ``sp{k}_plate``: the same six coordinates
  as the URDF's free-flyer (the ball's quaternion is ``w x y z`` in MuJoCo).
* Leg i of platform j is the body ``sp{j}_leg{i}_motor`` in plate j at the bottom joint
  centre, turned so that its z axis is the leg's home direction, with the two hinges of the
  universal joint (``_ux`` about x, then ``_uy`` about the turned y, as the URDF's cross
  link), and the body ``sp{j}_leg{i}_shaft`` on the slide ``sp{j}_leg{i}_actuator`` along z.
  The shaft frame sits at the top joint centre and the slide's ``ref`` is the home length,
  so the slide's position *is* the pin-to-pin length [m], as in the URDF.
* The ball joints are ``<equality><connect body1="…_shaft" body2="plate_{j+1}" anchor="0 0
  0"/>``: the shaft frame origin and the top joint centre coincide in the reference
  configuration (the home pose), where MuJoCo computes the anchor in the plate's frame.
* One ``<position>`` actuator per leg on its slide: ``ctrl`` is the commanded pin-to-pin
  length [m] (``ctrlrange`` the stroke), gain the config's ``leg.stiffness`` (so MuJoCo's
  servo is the leg spring of :mod:`assembler_pin.compliance.ee_stiffness`), damping and armature from
  :func:`actuator_gains`, ``forcerange`` the config's force limits. MuJoCo's actuator force is
  positive when it pushes the shaft out, i.e. compression: the package's leg force (tension
  positive) is its negative.
* Inertias and primitive geometry equal the URDF's (explicit ``<inertial>`` everywhere, so
  geoms add no mass). Geoms do not collide (``contype = conaffinity = 0``): the model is for
  the mechanism's statics and dynamics, not for contact.

Constraint softness: MuJoCo's equality constraints are soft. ``solref`` = (timeconst
:data:`EQUALITY_SOLREF`\\[0\\], damping ratio 1) and ``solimp`` = :data:`EQUALITY_SOLIMP` make
the loops stiff enough that the closure residual of a held pose stays well under a
millimetre at the default timestep :data:`TIMESTEP` (timeconst must stay above two
timesteps for MuJoCo to keep it). The statics cross-check does not depend on them
(see :mod:`assembler_pin.simulate`).
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..config.schema import AssemblerConfig
from .geometry import DIMENSIONS, LEGS_PER_PLATFORM, LegGeometry, leg_geometry
from .urdf import MATERIALS, cylinder_inertia, node_points, xml_document, xml_number, xml_vector

__all__ = [
    "ACTUATOR_ARMATURE",
    "ACTUATOR_KP",
    "ACTUATOR_KV",
    "EQUALITY_SOLIMP",
    "EQUALITY_SOLREF",
    "MJCF_FILENAME",
    "TIMESTEP",
    "MjcfLayout",
    "actuator_gains",
    "assembler_mjcf",
]

MJCF_FILENAME = "assembler.xml"
#: Reference position gain of a leg actuator [N/m] (the default ``leg.stiffness``: 0.1 mm of
#: length error per 100 N), at which :data:`ACTUATOR_KV` and :data:`ACTUATOR_ARMATURE` hold.
ACTUATOR_KP = 1.0e6
#: Velocity damping of each leg actuator at :data:`ACTUATOR_KP` [N s/m] (overdamps the slide's
#: armature: damping ratio 10).
ACTUATOR_KV = 2.0e4
#: Reflected inertia of each actuator's drive on its slide at :data:`ACTUATOR_KP` [kg] (MuJoCo
#: ``armature``): it keeps the stiff position loop stable at :data:`TIMESTEP`; it has no effect
#: on statics.
ACTUATOR_ARMATURE = 1.0
#: Integration timestep [s].
TIMESTEP = 1.0e-3
#: Equality (ball-joint) constraint reference: time constant [s] and damping ratio.
EQUALITY_SOLREF = (2.0e-3, 1.0)
#: Equality constraint impedance (dmin, dmax, width [m]).
EQUALITY_SOLIMP = (0.99, 0.999, 1.0e-3)


@dataclass(frozen=True)
class MjcfLayout:
    """Names in the MJCF, in the order MuJoCo numbers them.

    Attributes:
        plate_joints: (n, 4) names per moving plate: the x, y, z slides and the ball.
        leg_joints: (n, 6, 3) names per leg: ``ux``, ``uy`` hinges and the actuator slide.
        actuators: (6n,) actuator names, platform-major (``sp{j}_leg{i}``).
    """

    plate_joints: list[list[str]]
    leg_joints: list[list[list[str]]]
    actuators: list[str]

    @classmethod
    def of(cls, platforms: int) -> MjcfLayout:
        plate = [[names.plate_slide(j, a) for a in "xyz"] + [names.plate_joint(j)] for j in range(platforms)]
        legs = [
            [[names.leg(j, i, part) for part in ("ux", "uy", "actuator")] for i in range(LEGS_PER_PLATFORM)]
            for j in range(platforms)
        ]
        acts = [names.leg(j, i) for j in range(platforms) for i in range(LEGS_PER_PLATFORM)]
        return cls(plate, legs, acts)


def actuator_gains(stiffness: float) -> tuple[float, float, float]:
    """(kp [N/m], kv [N s/m], armature [kg]) of a leg servo whose stiffness is ``stiffness``.

    ``kp`` is the stiffness itself. Above :data:`ACTUATOR_KP` the armature grows with it, so
    the loop's natural frequency (and its stability at :data:`TIMESTEP`) stays that of the
    reference; ``kv`` keeps the reference damping ratio ``kv / (2 sqrt(kp · armature))``.
    """
    armature = ACTUATOR_ARMATURE * max(1.0, stiffness / ACTUATOR_KP)
    kv = ACTUATOR_KV * float(np.sqrt(stiffness * armature / (ACTUATOR_KP * ACTUATOR_ARMATURE)))
    return float(stiffness), kv, armature


def _quat_wxyz(rotation: np.ndarray) -> str:
    x, y, z, w = pin.Quaternion(rotation).coeffs()
    return xml_vector(np.array([w, x, y, z]))


def _inertial(body: ET.Element, mass: float, com: np.ndarray, diag: np.ndarray) -> None:
    # MuJoCo rejects a zero inertia on a moving body; massless links of the URDF (the cross
    # link, the top mounts) do not exist here.
    ET.SubElement(body, "inertial", pos=xml_vector(com), mass=xml_number(mass), diaginertia=xml_vector(diag))


def _cylinder_part(body: ET.Element, mass: float, radius: float, com_z: float, material: str) -> None:
    """Inertial and geom of a motor or shaft: a solid cylinder on the body's z axis, centred at
    ``com_z`` [m], twice ``|com_z|`` long (as in the URDF)."""
    length = 2.0 * abs(com_z)
    centre = np.array([0.0, 0.0, com_z])
    _inertial(body, mass, centre, cylinder_inertia(mass, radius, length))
    if length > 0:
        size = xml_vector(np.array([radius, 0.5 * length]))
        ET.SubElement(body, "geom", type="cylinder", size=size, pos=xml_vector(centre), material=material)


_Z_AXIS = np.array([0.0, 0.0, 1.0])


def _mjcf_header(root: ET.Element, cfg: AssemblerConfig) -> None:
    """Compiler, options (timestep, gravity [m/s²]), defaults, materials."""
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(
        root,
        "option",
        timestep=xml_number(TIMESTEP),
        gravity=xml_vector(np.array([0.0, 0.0, -cfg.gravity])),
        integrator="implicitfast",
    )
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", contype="0", conaffinity="0")
    ET.SubElement(
        default, "equality", solref=xml_vector(np.array(EQUALITY_SOLREF)), solimp=xml_vector(np.array(EQUALITY_SOLIMP))
    )
    asset = ET.SubElement(root, "asset")
    for name, rgba in MATERIALS.items():
        ET.SubElement(asset, "material", name=name, rgba=rgba)


def _add_plate(parent: ET.Element, cfg: AssemblerConfig, k: int) -> ET.Element:
    """The body of plate k in ``parent`` (plate k-1, or the world for plate 0): its three
    slides and ball (k ≥ 1), inertia, disc and node spheres."""
    dim, r = DIMENSIONS, cfg.plate.node_radius
    if k == 0:
        body = ET.SubElement(parent, "body", name=names.plate(0), pos="0 0 0")
    else:
        body = ET.SubElement(parent, "body", name=names.plate(k), pos=xml_vector(cfg.home_height * _Z_AXIS))
        j = k - 1
        for a, axis in zip("xyz", ("1 0 0", "0 1 0", "0 0 1"), strict=True):
            ET.SubElement(body, "joint", name=names.plate_slide(j, a), type="slide", axis=axis, limited="false")
        ET.SubElement(body, "joint", name=names.plate_joint(j), type="ball", limited="false")
    _inertial(body, cfg.plate.mass, np.zeros(3), cylinder_inertia(cfg.plate.mass, r, dim.plate_thickness))
    ET.SubElement(
        body, "geom", type="cylinder", size=xml_vector(np.array([r, 0.5 * dim.plate_thickness])), material="plate"
    )
    for p in node_points(cfg, k):
        ET.SubElement(
            body, "geom", type="sphere", size=xml_number(dim.node_sphere_radius), pos=xml_vector(p), material="node"
        )
    return body


def _add_leg(parent: ET.Element, cfg: AssemblerConfig, geo: LegGeometry, j: int, i: int, home_length: float) -> None:
    """Leg i of platform j in plate j's body: the motor body on the universal joint's two
    hinges, the shaft body on the actuator slide (``ref`` the home length ``home_length`` [m])."""
    leg, dim = cfg.leg, DIMENSIONS
    defl = leg.max_deflection
    _, _, armature = actuator_gains(leg.stiffness)
    n_ = functools.partial(names.leg, j, i)
    motor = ET.SubElement(
        parent,
        "body",
        name=n_("motor"),
        pos=xml_vector(geo.bottom_in_plate[j, i]),
        quat=_quat_wxyz(geo.leg_base_rotation[j, i]),
    )
    for part, axis in (("ux", "1 0 0"), ("uy", "0 1 0")):
        ET.SubElement(motor, "joint", name=n_(part), type="hinge", axis=axis, range=xml_vector(np.array([-defl, defl])))
    _cylinder_part(motor, leg.motor_mass, dim.motor_radius, leg.motor_com, "motor")
    shaft = ET.SubElement(motor, "body", name=n_("shaft"), pos=xml_vector(home_length * _Z_AXIS))
    ET.SubElement(
        shaft,
        "joint",
        name=n_("actuator"),
        type="slide",
        axis="0 0 1",
        ref=xml_number(home_length),
        armature=xml_number(armature),
        range=xml_vector(np.array([leg.min_length, leg.max_length])),
    )
    _cylinder_part(shaft, leg.shaft_mass, dim.shaft_radius, -leg.shaft_com, "shaft")


def _add_bodies(world: ET.Element, cfg: AssemblerConfig) -> None:
    """The nested bodies: plate 0, then per platform its legs and the next plate, the payload."""
    geo = leg_geometry(cfg)
    home_lengths = np.linalg.norm(geo.top_in_plate + cfg.home_height * _Z_AXIS - geo.bottom_in_plate, axis=-1)
    parent = _add_plate(world, cfg, 0)
    for j in range(cfg.platforms):
        for i in range(LEGS_PER_PLATFORM):
            _add_leg(parent, cfg, geo, j, i, home_lengths[j, i])
        parent = _add_plate(parent, cfg, j + 1)
    size = DIMENSIONS.payload_size
    payload = ET.SubElement(parent, "body", name=names.payload, pos=xml_vector(cfg.payload.offset * _Z_AXIS))
    m = cfg.payload.mass
    _inertial(payload, m, np.zeros(3), np.full(3, m * size**2 / 6.0))
    if cfg.payload.radius > 0:  # the sphere the package checks; radius 0: a point mass, no shape
        ET.SubElement(payload, "geom", type="sphere", size=f"{cfg.payload.radius!r}", material="payload")


def _add_equalities(root: ET.Element, cfg: AssemblerConfig, weld_ee: bool) -> None:
    """The ball joints (``connect``) and, with ``weld_ee``, the EE weld."""
    equality = ET.SubElement(root, "equality")
    for j in range(cfg.platforms):
        for i in range(LEGS_PER_PLATFORM):
            ET.SubElement(
                equality,
                "connect",
                name=names.leg(j, i, "ball"),
                body1=names.leg(j, i, "shaft"),
                body2=names.plate(j + 1),
                anchor="0 0 0",
            )
    if weld_ee:
        ET.SubElement(equality, "weld", name="ee_weld", body1=names.plate(cfg.platforms))


def _add_actuators(root: ET.Element, cfg: AssemblerConfig) -> None:
    """One position servo per leg (gains of :func:`actuator_gains`, stroke and force limits)."""
    leg = cfg.leg
    kp, kv, _ = actuator_gains(leg.stiffness)
    actuator = ET.SubElement(root, "actuator")
    for j in range(cfg.platforms):
        for i in range(LEGS_PER_PLATFORM):
            ET.SubElement(
                actuator,
                "position",
                name=names.leg(j, i),
                joint=names.leg(j, i, "actuator"),
                kp=xml_number(kp),
                kv=xml_number(kv),
                ctrlrange=xml_vector(np.array([leg.min_length, leg.max_length])),
                forcerange=xml_vector(np.array([-leg.max_tension, leg.max_compression])),
            )


def assembler_mjcf(cfg: AssemblerConfig, weld_ee: bool = False) -> str:
    """The MJCF text of the stack described by ``cfg`` (see module docstring); ``weld_ee`` adds
    the equality ``<weld name="ee_weld" body1="plate_n"/>`` holding the EE plate to the world
    (both ends held; its ``eq_data`` relative pose is the home one until set)."""
    root = ET.Element("mujoco", model="assembler")
    _mjcf_header(root, cfg)
    world = ET.SubElement(root, "worldbody")
    ET.SubElement(world, "light", name="sun", pos="0 0 3", dir="0 0 -1", directional="true")
    _add_bodies(world, cfg)
    _add_equalities(root, cfg, weld_ee)
    _add_actuators(root, cfg)
    note = "\n     Ball joints are equality constraints; each slide's position is the leg length [m]."
    return xml_document(root, cfg, note)
