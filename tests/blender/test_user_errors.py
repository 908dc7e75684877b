"""What a user hits in production, each in the user's own terms: a radius of 0 refused with its label, bad particle
coordinates explained with the panel's labels and readable numbers, a failed headless bake that says why, frames
outside a partial bake rebuilt live, Play From Cache refused without a cache, Auto showing what it means here,
Custom Normals in one panel, the scene range following the files, the frame number visible in the status.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import shutil
import sys
import tempfile
import types

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
api = addon.api
panels, properties, update = _support.addon_modules(addon, "blender.panels", "blender.properties", "blender.update")
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_user_errors_")
_support.clear_scene()
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 250
scene.frame_set(30)
surface = _support.add_sample_sequence()
settings = surface.meniscus
settings.is_surface = False
settings.cube_size = settings.render_cube_size = 1.5
settings.smoothing_iterations = 0
settings.is_surface = True


class _Recorder:
    """Stands in for a panel's layout: records every property drawn and every label, whatever nesting."""

    def __init__(self, record=None):
        self.record = record if record is not None else {"props": [], "labels": []}

    def __getattr__(self, name):  # row, column, box, split, ...: nested layouts record into the same lists
        if name in ("row", "column", "box", "split", "grid_flow", "column_flow"):
            return lambda *args, **kwargs: _Recorder(self.record)
        if name == "prop":
            return lambda data, prop, **kwargs: self.record["props"].append(prop)
        if name == "label":
            return lambda text="", **kwargs: self.record["labels"].append(text)
        if name == "operator":
            return lambda *args, **kwargs: _Recorder(self.record)
        return lambda *args, **kwargs: _Recorder(self.record)

    def __setattr__(self, name, value):  # .active, .enabled, .alert, .object_name
        if name == "record":
            object.__setattr__(self, name, value)
        else:
            self.record.setdefault(name, []).append(value)


class _Context:
    def __init__(self, sidebar_width):
        self.active_object = surface
        self.scene = scene
        self.preferences = bpy.context.preferences
        self.region = type("Region", (), {"width": sidebar_width})()


def draw(panel, sidebar_width=300):
    """What a panel draws for the surface (its draw function called with a recording layout)."""
    layout = _Recorder()
    fake = types.SimpleNamespace(layout=layout)
    for name in ("group", "draw_before", "draw_after"):
        value = getattr(panel, name, None)
        setattr(fake, name, types.MethodType(value, fake) if callable(value) else value)
    panel.draw(fake, _Context(sidebar_width))
    return layout.record


def test_adding_a_sequence_sets_the_scene_range_to_the_files():
    check((scene.frame_start, scene.frame_end) == (_support.SAMPLE_FIRST, _support.SAMPLE_LAST),
          (scene.frame_start, scene.frame_end))


def test_radius_zero_or_negative_is_refused_with_the_panel_label():
    for radius in (0.0, -0.01):
        settings.particle_radius = radius
        check(abs(settings.particle_radius - radius) < 1e-6, f"{radius} stored as {settings.particle_radius}: clamped")
        check(settings.status_is_error and "Particle Radius" in settings.status and "particle_radius" not in
              settings.status, settings.status)
        check(len(surface.data.polygons) == 0, "a refused radius must not leave a surface")
    settings.particle_radius = _support.SAMPLE_RADIUS
    check(not settings.status_is_error and len(surface.data.polygons) > 0, settings.status)


def _particle_file(name, positions):
    path = os.path.join(_temporary.name, name)
    np.save(path, positions.astype(np.float32))
    return path


def test_bad_coordinates_are_explained_in_panel_terms():
    positions = api.read_particles(_support.SAMPLE_DIR / "double_dam_break_0030.vtk").positions
    invalid = os.path.join(_temporary.name, "invalid")
    os.makedirs(invalid)
    positions_nan = positions.copy()
    positions_nan[5] = np.nan
    positions_far = positions.copy()
    positions_far[5] = 3.4e38
    _particle_file("invalid/bad_0001.npy", positions_nan)
    _particle_file("invalid/bad_0002.npy", positions_far)
    settings.is_surface = False
    settings.file_pattern = os.path.join(invalid, "bad_####.npy")
    settings.frame_offset, settings.frame_start, settings.frame_end = -29, 1, 2
    settings.is_surface = True
    try:
        scene.frame_set(30)
        status = settings.status
        check(settings.status_is_error and "'Skip Invalid Particles'" in status and "skip_invalid" not in status and
              "--" not in status and not status.startswith("Error"), status)
        scene.frame_set(31)
        status = settings.status
        check(settings.status_is_error and "3.4e+38" in status and "3399999" not in status and
              not status.startswith("Error"), status)  # 'Error: ' marks the unexpected, printed with a traceback
    finally:
        settings.is_surface = False  # three fields, one rebuild
        settings.file_pattern = _support.SAMPLE_PATTERN
        settings.frame_offset, settings.frame_start, settings.frame_end = 0, _support.SAMPLE_FIRST, _support.SAMPLE_LAST
        settings.is_surface = True
        scene.frame_set(30)


def test_a_failed_headless_bake_says_why():
    folder = os.path.join(_temporary.name, "half_broken")
    os.makedirs(folder)
    for frame in (30, 31):
        shutil.copy(_support.SAMPLE_DIR / f"double_dam_break_00{frame}.vtk", folder)
        with open(os.path.join(folder, f"double_dam_break_00{frame}.vtk"), "r+b") as broken:
            broken.truncate(3000)
    settings.file_pattern = os.path.join(folder, "double_dam_break_####.vtk")
    settings.cache_pattern = os.path.join(_temporary.name, "broken_cache", "fluid_####.npz")
    try:
        bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=30, frame_end=31)
        raise AssertionError("a bake of broken files reported success")
    except RuntimeError as error:  # an operator's ERROR report, as a script sees it
        message = str(error)
        check("Baked 0 of 2" in message and "double_dam_break_0030.vtk" in message, message)
    finally:
        settings.file_pattern = _support.SAMPLE_PATTERN
        settings.cache_pattern = ""


def test_play_from_cache_needs_a_cache_and_partial_bakes_fill_in_live():
    settings.cache_pattern = os.path.join(_temporary.name, "partial", "fluid_####.npz")
    scene.frame_set(30)
    shown = _support.mesh_counts(surface)
    settings.use_cache = True
    check(not settings.use_cache and "Bake" in settings.status, f"ticked without a cache: {settings.status}")
    check(_support.mesh_counts(surface) == shown, "the surface must stay as it was")
    check(draw(panels.MENISCUS_PT_cache)["enabled"][-1] is False, "Play From Cache offered without a cache")
    result = bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=30, frame_end=31)
    check(result == {"FINISHED"} and settings.use_cache, (result, settings.use_cache))
    scene.frame_set(33)  # baked 30-31 only: 33 comes from its particle file
    check(not settings.status_is_error and len(surface.data.polygons) > 0 and
          "double_dam_break_0033.vtk" in settings.status, settings.status)
    scene.frame_set(31)
    check("(cache)" in settings.status, settings.status)
    settings.use_cache = False
    settings.cache_pattern = ""


def test_auto_shows_what_it_means_here():
    settings.threads_auto = settings.memory_budget_auto = True
    labels = draw(panels.MENISCUS_PT_performance)["labels"]
    cores = os.environ.get("OMP_NUM_THREADS") or str(os.cpu_count())
    # Each automatic value: its label, then what Auto means here on the row below.
    meaning = f"the free ones of {cores} cores" if sys.platform.startswith("linux") else f"all {cores} cores"
    check(labels[labels.index("Threads:") + 1] == meaning or
          labels[labels.index("Threads:") + 1] == f"{cores} (OMP_NUM_THREADS)", labels)
    meaning = labels[labels.index("Memory Limit:") + 1]
    check(meaning.startswith("75 % of ") and "GiB" in meaning, labels)
    drawn = draw(panels.MENISCUS_PT_performance)["props"]
    check("threads" not in drawn and "memory_budget" not in drawn, f"stale manual values drawn: {drawn}")


def test_custom_normals_in_one_panel():
    holders = [panel.__name__ for panel in panels.classes if panel is not panels.MENISCUS_PT_main and
               "use_custom_normals" in draw(panel)["props"]]
    check(holders == ["MENISCUS_PT_normals"], holders)


def test_status_shows_the_frame_number_at_the_default_sidebar_width():
    scene.frame_set(37)
    # The default sidebar is about 220 pixels wide at scale 1 (Blender's UI_SIDEBAR_PANEL_WIDTH).
    labels = draw(panels.MENISCUS_PT_main, sidebar_width=220)["labels"]
    width = panels.status_width(_Context(220))
    check(any("0037" in label for label in labels) and all(len(label) <= width for label in labels), labels)


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
