"""The stack in Meshcat: :class:`StackViewer` is a :class:`~assembler_pin.viz.scene.StackScene`
(the main stack, animations, the page) that also draws beside the stack: the initial pose as a
ghost, the helper arm, point clouds, a carrier arm, the loaded pose and the EE's compliance
ellipsoid. World frame O (z up), SI units.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt
from pinocchio.visualize import MeshcatVisualizer

from ..exceptions import AssemblerError, ViewerError
from ..kinematics import PlateArrays
from ..state import StackState
from . import animation as anim_mod
from . import compliance, drawing
from . import placements as pl
from .colors import ARM_LINK_RGBA, CARRIER_RGBA, COMPLIANCE_RGBA, GHOST_RGBA, LOADED_RGBA
from .scene import Pose, StackScene

if TYPE_CHECKING:
    from ..walk import WalkResult

__all__ = ["StackViewer"]


class StackViewer(StackScene):
    """Meshcat view of an Assembler (arguments and attributes: :class:`~assembler_pin.viz.scene.StackScene`).

    Besides the main stack (:meth:`display`, :meth:`animate`) it draws, each under its own
    meshcat path and named in the page's legend: a ghost pose, the helper arm, point clouds,
    a carrier, the loaded pose and the compliance ellipsoid; and it animates a walk
    (:meth:`show_walk`).
    """

    def show_ghost(
        self, pose: Pose, name: str = "initial", rgba: npt.ArrayLike = GHOST_RGBA, label: str = "initial pose (ghost)"
    ) -> None:
        """Draw a second pose as a translucent ghost (default: the initial pose, green) under
        ``{prefix}_{name}``, named ``label`` in the legend. Its payload is an orange wireframe:
        a translucent cube over the solid payload would tint it."""
        plates = pl.as_plates(self.am, pose)
        root = self.scene_path(name)
        if name not in self._ghosts:
            self._ghosts[name] = self._make_visualizer(root, rgba)
            drawing.wireframe_payload(self._ghosts[name], self.am)
        self._place(self._ghosts[name], plates)
        self._add_root(root, pl.stack_points(self.am, plates))
        self._legend[root] = (np.asarray(rgba)[:3], label)

    def show_helper_arm(self, points: npt.ArrayLike, name: str = "helper_arm") -> None:
        """Draw the helper arm from its (n+2, 3) world points [m] (base, the n joint clusters,
        tip): violet links, dark violet joint clusters."""
        pts = drawing.checked_points(points)
        drawing.draw_helper_arm(self.meshcat[name], pts)
        self._add_root(name, pts)
        self._legend[name] = (ARM_LINK_RGBA, "helper arm")

    def show_points(self, name: str, points: npt.ArrayLike, colors: npt.ArrayLike, size: float = 0.03) -> None:
        """A point cloud under the meshcat path ``name``: (N, 3) world points [m] and (N, 3)
        RGB colors in [0, 1]; the camera frames it with the rest."""
        pts, rgb = np.asarray(points, dtype=float), np.asarray(colors, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or rgb.shape != pts.shape or not np.all(np.isfinite(pts)):
            raise ViewerError(f"points and colors must be finite (N, 3) arrays, got {pts.shape} and {rgb.shape}")
        cloud = mg.PointCloud(position=pts.T.astype(np.float32), color=rgb.T.astype(np.float32), size=size)
        self.meshcat[name].set_object(cloud)
        self._add_root(name, pts)

    def show_carrier(self, carrier, q: npt.ArrayLike, name: str = "carrier") -> None:
        """Draw a carrier arm (:class:`~assembler_pin.carrier.Carrier`) at joint angles ``q``."""
        q = carrier.check_q(q)
        viz = MeshcatVisualizer(carrier.model, None, carrier.visual_model)
        viz.initViewer(viewer=self.meshcat)
        viz.loadViewerModel(rootNodeName=name)
        drawing.paint_meshes(viz, CARRIER_RGBA)
        viz.display(q)
        self._carrier_viz = viz
        self._add_root(name, carrier.joint_points(q))
        self._legend[name] = (CARRIER_RGBA, f"carrier arm: {carrier.name}")

    def show_comparison(
        self, initial: StackState | None, optimized: StackState | None, arm_points: npt.ArrayLike | None = None
    ) -> None:
        """The paper's comparison: optimized pose solid (force colors), initial as a ghost
        (with only the initial pose, it is drawn solid); the helper arm if given; framed."""
        solid = optimized if optimized is not None else initial
        if solid is None:
            raise AssemblerError("nothing to show: both the initial and the optimized state are missing")
        self.display(solid)
        if optimized is not None and initial is not None:
            self.show_ghost(initial)
        if arm_points is not None:
            self.show_helper_arm(arm_points)
        self.frame()

    def _shown_plates(self, pose: Pose | None) -> PlateArrays:
        if pose is not None:
            return pl.as_plates(self.am, pose)
        if self.state is None:
            raise AssemblerError("nothing drawn yet: call display() first or give a pose")
        return self.state.plates

    def show_loaded(
        self, pose: Pose | None = None, exaggerate: float | None = None, wrench: npt.ArrayLike | None = None
    ) -> compliance.LoadedView:
        """Draw the loaded pose (a teal ghost ``{prefix}_loaded``) of the legs commanded to the
        lengths of ``pose`` (default: the pose shown): every plate moved ``exaggerate`` times its
        displacement from the rigid pose (default: a 1-2-5 factor drawing the largest about
        5 cm), the factor and the EE's true sag in the legend (:func:`.compliance.loaded_view`)."""
        view = compliance.loaded_view(self.am, self._shown_plates(pose), exaggerate, wrench)
        sag = 1e3 * float(np.linalg.norm(view.loaded.translation))
        label = f"loaded pose, displacements × {view.factor:g} (EE sag {sag:.3g} mm)"
        self.show_ghost(view.plates, "loaded", LOADED_RGBA, label)
        return view

    def show_ellipsoid(self, pose: Pose | None = None, force: float = 100.0) -> compliance.EllipsoidView:
        """Draw the EE's compliance ellipsoid ``{prefix}_compliance`` at the EE plate's origin of
        ``pose`` (default: the pose shown): semi-axes along the principal directions of the
        translational compliance, each the sag under ``force`` [N] along it
        (:func:`.compliance.ellipsoid_view`); the force and the largest sag in the legend."""
        view = compliance.ellipsoid_view(self.am, self._shown_plates(pose), force)
        root = self.scene_path("compliance")
        compliance.draw_ellipsoid(self.meshcat[root]["ellipsoid"], view, COMPLIANCE_RGBA)
        self._add_root(root, view.extent)
        self._legend[root] = (COMPLIANCE_RGBA, view.label)
        return view

    #: Phases named one per row in the legend of :meth:`show_walk`; the rest are counted.
    WALK_LEGEND_PHASES = 12

    def show_walk(
        self, walk: WalkResult, fps: float = 10.0, play: bool = True, repetitions: int = 1
    ) -> list[anim_mod.PhaseSpan]:
        """Animate a :class:`~assembler_pin.walk.WalkResult`: one frame per sample of every phase
        in order, at ``fps`` frames per second; each leg's force sleeve coloured by the forces of
        its phase's support, the held foot (plate 0, plate n, or both) marked by a disc in the
        phase's colour (:data:`~.animation.WALK_PHASE_RGB`), a brown disc at every foothold
        (``{prefix}_walk/footholds/<k>``), the phase's name above the walk frame by frame
        (``{prefix}_walk/labels/<kind>``), and in the legend each phase with its frames and
        seconds. The legs' force colour is the sleeve's, joint to joint, on one scale for the
        whole walk (its largest force, the colour bar's). Returns the phases' spans.

        Raises:
            ViewerError: the walk has no sample, or ``fps`` is not a positive number.
        """
        frames = anim_mod.walk_frames(walk)
        if not frames:
            raise ViewerError(f"the walk has no sample to animate ({walk.reason})")
        if not (isinstance(fps, (int, float)) and 0 < fps < 1e4):
            raise ViewerError(f"fps must be a number in (0, 10000), got {fps!r}")
        self.display(frames[0].plates, color_forces=False, mark_violations=False)
        scale = anim_mod.animation_scale([f.forces for f in frames], self.am.config.leg, self.force_scale)
        anim_mod.make_force_bands(self.meshcat[self.scene_path("force_bands")], self.am, scale)
        self._add_root(self.scene_path("force_bands"))
        root = self.scene_path("walk")
        anim_mod.make_walk_markers(self.meshcat[root], self.am, walk.footholds)
        feet = np.array([f.translation for f in walk.footholds])
        top = max(float(pl.stack_points(self.am, f.plates)[:, 2].max()) for f in frames)
        label = np.array([feet[:, 0].mean(), feet[:, 1].min(), top + 0.12])
        anim_mod.make_phase_labels(self.meshcat[root], label)
        self._add_root(root, np.vstack([feet, label]))
        animation = anim_mod.build_walk_animation(self, frames, fps, root, scale)
        self.meshcat.set_animation(animation, play=play, repetitions=repetitions)
        step = max(1, len(frames) // 50)
        self._extra_points.update(
            {f"anim{k}": pl.stack_points(self.am, f.plates) for k, f in enumerate(frames[::step])}
        )
        self._animated = True
        self._place(self.viz, frames[0].plates)
        spans = anim_mod.phase_spans(frames, fps)
        self.force_range = scale  # where the sleeves saturate: the whole walk's forces
        self.forces_shown = True
        self._walk_legend(spans, root)
        peak = max(float(np.abs(f.forces).max()) for f in frames)
        verdict = "valid" if walk.success else f"not possible ({walk.reason[:80]})"
        self.set_title(f"Walk over {len(walk.footholds)} footholds: {verdict}; peak max|F| {peak:.1f} N")
        return spans

    def _walk_legend(self, spans: list[anim_mod.PhaseSpan], root: str) -> None:
        """The footholds and every phase (its kind's colour, frames and seconds) in the legend."""
        for key in [k for k in self._legend if k.startswith(root)]:
            del self._legend[key]
        self._legend[f"{root}/footholds"] = (anim_mod.FOOTHOLD_RGBA[:3], "foothold")
        shown = spans[: self.WALK_LEGEND_PHASES]
        for s in shown:
            self._legend[f"{root}/phase{s.phase}"] = (anim_mod.WALK_PHASE_RGB[s.kind], f"held foot, {s.label()}")
        if len(spans) > len(shown):
            rest = spans[len(shown)]
            self._legend[f"{root}/more"] = (
                anim_mod.WALK_PHASE_RGB[rest.kind],
                f"… {len(spans) - len(shown)} more phases, from frame {rest.first} ({rest.start:.1f} s)",
            )
