"""First light: the bundled double dam break becomes a surface that follows the frame, shades and renders.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
         -- --addon-path build/addon
"""
import os
import shutil
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
update, mesh_update = _support.addon_modules(addon, "blender.update", "blender.mesh_update")

_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_test_")


def use_fast_settings(obj):
    """Coarse cells and no post-processing: ~10x faster frames for tests that check plumbing, not surface quality."""
    settings = obj.meniscus
    settings.is_surface = False  # one rebuild after all fields, not one per field
    settings.cube_size = 1.0
    settings.render_cube_size = 1.0
    settings.smoothing_iterations = 0
    settings.decimate_barnacles = False
    settings.normal_smoothing_iterations = 0
    settings.is_surface = True


def test_add_sequence_sets_up_object():
    settings = surface.meniscus
    check(settings.is_surface, "object not marked as a surface")
    check(settings.file_pattern.endswith("double_dam_break_####.vtk"), settings.file_pattern)
    check((settings.frame_start, settings.frame_end) == (_support.SAMPLE_FIRST, _support.SAMPLE_LAST),
          f"frame range {settings.frame_start}-{settings.frame_end}")
    check(abs(settings.particle_radius - _support.SAMPLE_RADIUS) < 1e-9, "particle radius not taken over")
    check(scene.render.use_lock_interface, "Lock Interface must be on for rendering with frame handlers")
    check(bpy.context.view_layer.objects.active == surface, "new surface should be active")
    check(len(surface.data.materials) == 1 and surface.data.materials[0].use_nodes, "water material missing")
    names = {node.bl_idname for node in surface.data.materials[0].node_tree.nodes}
    check("ShaderNodeBsdfPrincipled" in names, names)


def test_frames_change_the_mesh():
    scene.frame_set(25)
    first = mesh_counts(surface)
    check(first[0] > 0 and first[1] > 0, f"empty surface at frame 25: {surface.meniscus.status}")
    check(not surface.meniscus.status_is_error, surface.meniscus.status)
    check("double_dam_break_0025.vtk" in surface.meniscus.status, surface.meniscus.status)
    check("12,096 particles" in surface.meniscus.status, surface.meniscus.status)
    scene.frame_set(26)
    second = mesh_counts(surface)
    check(second[0] > 0 and second[1] > 0, "empty surface at frame 26")
    check(first != second, f"mesh did not change between frames 25 and 26: {first}")
    triangles = mesh_update.read_triangles(surface.data)
    check(len(triangles) == second[1] and triangles.max() < second[0], "loops do not form triangles")
    check(all(polygon.loop_total == 3 for polygon in surface.data.polygons[:100]), "polygons are not triangles")


def test_faces_smooth_and_normals_unit_and_outward():
    scene.frame_set(30)
    mesh = surface.data
    smooth = np.empty(len(mesh.polygons), dtype=bool)
    mesh.polygons.foreach_get("use_smooth", smooth)
    check(smooth.all(), "all faces should be shaded smooth")
    if mesh_update.CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
        check(mesh.use_auto_smooth, "custom normals need use_auto_smooth before Blender 4.1")
    check(mesh.has_custom_normals, "custom normals were not set")

    vertices = mesh_update.read_vertices(mesh).astype(np.float64)
    triangles = mesh_update.read_triangles(mesh)
    normals = mesh_update.read_corner_normals(mesh).astype(np.float64)  # per corner, custom normals included
    lengths = np.linalg.norm(normals, axis=1)
    check(np.allclose(lengths, 1.0, atol=1e-3), f"normal lengths in [{lengths.min()}, {lengths.max()}]")

    # Oriented outward, three ways: the mesh encloses positive volume; shading normals agree with the faces'
    # winding; and they point away from the centre of their connected component.
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    face_normals = np.cross(b - a, c - a)
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    check(volume > 0, f"enclosed volume {volume} should be positive (triangles wound counter-clockwise)")
    agreement = np.einsum("ij,ij->i", normals.reshape(-1, 3, 3).mean(axis=1), face_normals) > 0
    check(agreement.mean() > 0.95, f"only {agreement.mean():.1%} of faces agree with their shading normals")

    labels = _support.connected_components(len(vertices), triangles)
    _, inverse, sizes = np.unique(labels, return_inverse=True, return_counts=True)
    centroids = np.zeros((len(sizes), 3))
    np.add.at(centroids, inverse, vertices)
    centroids /= sizes[:, None]
    corner_vertices = triangles.reshape(-1)
    outward = np.einsum("ij,ij->i", normals, vertices[corner_vertices] - centroids[inverse[corner_vertices]]) > 0
    check(outward.mean() > 0.6, f"only {outward.mean():.1%} of normals point away from their component centre")
    print(f"     {len(vertices)} vertices, {len(sizes)} components, volume {volume:.4f} m^3, "
          f"{outward.mean():.1%} outward, {agreement.mean():.1%} agree")


def test_velocity_attribute():
    scene.frame_set(31)
    velocity = mesh_update.read_point_vectors(surface.data, "velocity")
    check(velocity is not None, "no 'velocity' attribute")
    attribute = surface.data.attributes["velocity"]
    check((attribute.domain, attribute.data_type) == ("POINT", "FLOAT_VECTOR"), (attribute.domain, attribute.data_type))
    check(len(velocity) == len(surface.data.vertices), "velocity count != vertex count")
    check(np.isfinite(velocity).all(), "non-finite velocities")
    speeds = np.linalg.norm(velocity, axis=1)
    # Dam-break water falls and sloshes at metres per second; the values are the data's m/s, not per frame.
    check(0.1 < speeds.max() < 50.0, f"implausible speeds up to {speeds.max()} m/s")


def test_no_orphan_meshes_over_many_frame_changes():
    use_fast_settings(surface)  # from here on; the tests above judged the default (production) settings
    meshes = len(bpy.data.meshes)
    mesh = surface.data
    for step in range(50):
        scene.frame_set(_support.SAMPLE_FIRST + step % 20)
    check(len(bpy.data.meshes) == meshes, f"mesh datablocks grew from {meshes} to {len(bpy.data.meshes)}")
    check(surface.data == mesh, "the surface must keep reusing its one mesh")
    check(mesh.users == 1, f"mesh has {mesh.users} users")


def _sequence_copy_with_faults():
    """A copy of the sample with frame 25 missing and frame 26 broken (a truncated file)."""
    folder = os.path.join(_temporary.name, "faulty")
    os.makedirs(folder)
    for frame in range(_support.SAMPLE_FIRST, _support.SAMPLE_LAST + 1):
        name = f"double_dam_break_{frame:04d}.vtk"
        if frame == 25:
            continue
        if frame == 26:
            with open(os.path.join(_support.SAMPLE_DIR, name), "rb") as source:
                data = source.read()
            with open(os.path.join(folder, name), "wb") as target:
                target.write(data[:len(data) // 3])
            continue
        shutil.copy(os.path.join(_support.SAMPLE_DIR, name), folder)
    return os.path.join(folder, "double_dam_break_####.vtk")


def test_missing_and_broken_frames_leave_empty_mesh_and_status():
    faulty = _support.add_sample_sequence(_sequence_copy_with_faults())
    use_fast_settings(faulty)
    scene.frame_set(24)
    check(mesh_counts(faulty)[0] > 0 and not faulty.meniscus.status_is_error, faulty.meniscus.status)

    scene.frame_set(25)  # missing
    check(mesh_counts(faulty) == (0, 0), f"missing frame should give an empty mesh, got {mesh_counts(faulty)}")
    check(faulty.meniscus.status_is_error and "Missing" in faulty.meniscus.status, faulty.meniscus.status)
    check("double_dam_break_0025.vtk" in faulty.meniscus.status, faulty.meniscus.status)
    check(mesh_counts(surface)[0] > 0, "a fault in one surface must not affect another")

    scene.frame_set(26)  # broken: the reader raises, the handler must not
    check(mesh_counts(faulty) == (0, 0), "broken frame should give an empty mesh")
    check(faulty.meniscus.status_is_error and faulty.meniscus.status, "broken frame should report an error")
    print(f"     broken frame status: {faulty.meniscus.status}")

    scene.frame_set(27)  # and it recovers
    check(mesh_counts(faulty)[0] > 0 and not faulty.meniscus.status_is_error, faulty.meniscus.status)

    faulty.meniscus.file_pattern = os.path.join(_temporary.name, "nowhere", "x_####.vtk")
    check(mesh_counts(faulty) == (0, 0) and faulty.meniscus.status_is_error, faulty.meniscus.status)
    faulty.meniscus.file_pattern = "no frame number.vtk"
    check(mesh_counts(faulty) == (0, 0) and faulty.meniscus.status_is_error, faulty.meniscus.status)
    bpy.data.objects.remove(faulty)


def test_out_of_range_modes():
    settings = surface.meniscus
    scene.frame_set(_support.SAMPLE_LAST)
    last = mesh_counts(surface)
    scene.frame_set(_support.SAMPLE_FIRST)
    first = mesh_counts(surface)

    settings.out_of_range = "HOLD"
    scene.frame_set(100)
    check(mesh_counts(surface) == last, "HOLD after the range should show the last frame")
    scene.frame_set(1)
    check(mesh_counts(surface) == first, "HOLD before the range should show the first frame")

    settings.out_of_range = "LOOP"
    scene.frame_set(_support.SAMPLE_LAST + 1)
    check(mesh_counts(surface) == first, "LOOP should wrap to the first frame")

    settings.out_of_range = "BLANK"
    check(mesh_counts(surface) == (0, 0), "changing the mode should rebuild at once: BLANK shows nothing")
    check(not settings.status_is_error, "outside the range in BLANK mode is not an error")

    settings.frame_offset = -10  # scene frame 40 -> file frame 30
    check(mesh_counts(surface)[0] > 0 and "double_dam_break_0030" in settings.status, settings.status)
    settings.frame_offset = 0
    settings.out_of_range = "HOLD"


def test_motion_blur_subframes_do_not_rebuild():
    scene.frame_set(30)
    status = surface.meniscus.status
    check(not update.update_surface(surface, scene), "an unchanged frame must not be rebuilt")
    for frame, subframe in ((29, 0.75), (30, 0.25)):  # the shutter steps around frame 30
        scene.frame_set(frame, subframe=subframe)
        check(surface.meniscus.status == status, f"subframe {frame + subframe} rebuilt: {surface.meniscus.status}")
    scene.frame_set(30, subframe=0.5)  # past the middle: the next file
    check("double_dam_break_0031" in surface.meniscus.status, surface.meniscus.status)
    scene.frame_set(30)


def test_parameter_edit_rebuilds():
    scene.frame_set(30)
    before = mesh_counts(surface)
    surface.meniscus.cube_size = 2.0  # the update callback rebuilds at once, without a frame change
    coarser = mesh_counts(surface)
    check(coarser[1] < before[1], f"doubling the cube size should reduce triangles: {before} -> {coarser}")
    surface.meniscus.cube_size = 1.0
    check(mesh_counts(surface) == before, "restoring the cube size should restore the mesh")


def test_without_custom_normals():
    surface.meniscus.use_custom_normals = False
    check(not surface.data.has_custom_normals, "custom normals left behind")
    if mesh_update.CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
        check(not surface.data.use_auto_smooth, "auto smooth should be off without custom normals")
    check(mesh_counts(surface)[0] > 0, surface.meniscus.status)
    surface.meniscus.use_custom_normals = True
    check(surface.data.has_custom_normals, "custom normals not restored")


def test_edit_mode_objects_are_skipped():
    scene.frame_set(30)
    at_30 = mesh_counts(surface)
    bpy.context.view_layer.objects.active = surface
    bpy.ops.object.mode_set(mode="EDIT")
    scene.frame_set(33)  # must neither crash nor swap the geometry under the edit
    bpy.ops.object.mode_set(mode="OBJECT")
    check(mesh_counts(surface) == at_30, "the mesh changed while in Edit Mode")
    scene.frame_set(34)
    check(mesh_counts(surface) != at_30 and mesh_counts(surface)[0] > 0, "no rebuild after leaving Edit Mode")


def test_undo_shows_the_current_frame():
    global surface, scene
    name = surface.name
    scene.frame_set(30)
    bpy.ops.ed.undo_push(message="before edit")
    surface.meniscus.cube_size = 2.0
    bpy.ops.ed.undo_push(message="coarse cells")
    scene.frame_set(33)
    check(bpy.ops.ed.undo() == {"FINISHED"}, "undo failed")
    # Undo reloads data-blocks: references held across it are dangling, look everything up again.
    scene = bpy.context.scene
    surface = bpy.data.objects[name]
    check(abs(surface.meniscus.cube_size - 1.0) < 1e-9, f"undo restored cube size {surface.meniscus.cube_size}, not 1.0")
    # Whatever frame undo leaves the scene at, the surface must show that frame with the restored parameters.
    frame = scene.frame_current
    check(f"double_dam_break_{frame:04d}" in surface.meniscus.status, f"at frame {frame}: {surface.meniscus.status}")
    shown = mesh_counts(surface)
    check(bpy.ops.meniscus.reload(all_surfaces=True) == {"FINISHED"}, "reload failed")
    check(mesh_counts(surface) == shown, f"after undo the mesh {shown} is not frame {frame}'s {mesh_counts(surface)}")


def test_reload_operator():
    scene.frame_set(30)
    counts = mesh_counts(surface)
    check(bpy.ops.meniscus.reload(all_surfaces=True) == {"FINISHED"}, "reload failed")
    check(mesh_counts(surface) == counts, "reload changed the mesh of an unchanged file")


def test_render_small_frame():
    scene.frame_set(30)
    camera_data = bpy.data.cameras.new("Test Camera")
    camera = bpy.data.objects.new("Test Camera", camera_data)
    scene.collection.objects.link(camera)
    camera.location = (1.5, -3.2, 2.4)
    camera.rotation_euler = (np.radians(60), 0.0, 0.0)
    scene.camera = camera
    if scene.world is None:
        scene.world = bpy.data.worlds.new("Test World")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)

    render = scene.render
    render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 4
    scene.cycles.use_denoising = False  # Debian's Blender has no OpenImageDenoise
    render.resolution_x, render.resolution_y, render.resolution_percentage = 64, 36, 100
    render.image_settings.file_format = "PNG"
    render.filepath = os.path.join(_temporary.name, "render.png")
    bpy.ops.render.render(write_still=True)
    check(os.path.isfile(render.filepath), "no PNG written")
    image = bpy.data.images.load(render.filepath)
    pixels = np.array(image.pixels[:]).reshape(-1, 4)[:, :3]
    check(pixels.size == 64 * 36 * 3, f"unexpected image size {image.size[:]}")
    check(np.ptp(pixels, axis=0).max() > 0.05, "the render is (almost) a single colour")
    check(not surface.meniscus.status_is_error, surface.meniscus.status)


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
