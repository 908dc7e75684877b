"""A default water material, so a new surface renders as water without any setup.

Clear water: a Principled BSDF with full transmission and the IOR of water, plus a faint blue absorption in the
volume so that deep water reads bluer than shallow water (as it does in reality).
"""
import bpy

WATER_MATERIAL_NAME = "Meniscus Water"
WATER_IOR = 1.33
_SURFACE_TINT = (0.85, 0.95, 1.0, 1.0)
_ABSORPTION_COLOR = (0.55, 0.8, 0.95, 1.0)
_SHADOW_TINT = (0.9, 0.96, 1.0, 1.0)  # water still dims the light a little
# Per scene unit (metres for the usual scale): a metre of water absorbs noticeably, a few centimetres hardly.
_ABSORPTION_DENSITY = 1.5


def _set_input(node, names, value):
    """Sets the first existing input among names; Principled BSDF inputs were renamed in Blender 4.0."""
    for name in names:
        socket = node.inputs.get(name)
        if socket is not None:
            socket.default_value = value
            return True
    return False


def _build_nodes(material):
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()

    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (300, 0)
    principled = tree.nodes.new("ShaderNodeBsdfPrincipled")
    principled.location = (0, 0)
    _set_input(principled, ("Base Color",), _SURFACE_TINT)
    _set_input(principled, ("Transmission Weight", "Transmission"), 1.0)  # 4.x name first, then 3.x
    _set_input(principled, ("IOR",), WATER_IOR)
    _set_input(principled, ("Roughness",), 0.0)

    # Light reaching the ground through water arrives only as caustics, which path tracing at usual sample counts
    # leaves out (or renders as fireflies): everything under the surface would be in shadow and the water would
    # look black. The usual remedy: shadow rays see the surface as transparent, so the ground stays lit.
    light_path = tree.nodes.new("ShaderNodeLightPath")
    light_path.location = (-300, 250)
    transparent = tree.nodes.new("ShaderNodeBsdfTransparent")
    transparent.location = (-300, -350)
    transparent.inputs["Color"].default_value = _SHADOW_TINT
    surface = tree.nodes.new("ShaderNodeMixShader")
    surface.location = (200, 100)
    output.location = (450, 0)
    tree.links.new(light_path.outputs["Is Shadow Ray"], surface.inputs["Fac"])
    tree.links.new(principled.outputs["BSDF"], surface.inputs[1])
    tree.links.new(transparent.outputs["BSDF"], surface.inputs[2])
    tree.links.new(surface.outputs["Shader"], output.inputs["Surface"])

    absorption = tree.nodes.new("ShaderNodeVolumeAbsorption")
    absorption.location = (0, -420)
    absorption.inputs["Color"].default_value = _ABSORPTION_COLOR
    absorption.inputs["Density"].default_value = _ABSORPTION_DENSITY
    tree.links.new(absorption.outputs["Volume"], output.inputs["Volume"])


def _configure_viewport(material):
    # EEVEE shows refraction only with these flags; their names depend on the EEVEE generation, hence the guards.
    material.diffuse_color = (0.6, 0.8, 1.0, 0.6)
    for flag in ("use_screen_refraction", "use_raytrace_refraction"):
        if hasattr(material, flag):
            setattr(material, flag, True)
    if hasattr(material, "blend_method"):
        material.blend_method = "BLEND"
    if hasattr(material, "show_transparent_back"):
        material.show_transparent_back = False


def ensure_water_material():
    """The shared water material, created on first use; a material the user edited is kept as it is."""
    material = bpy.data.materials.get(WATER_MATERIAL_NAME)
    if material is None:
        material = bpy.data.materials.new(WATER_MATERIAL_NAME)
        _build_nodes(material)
        _configure_viewport(material)
    return material


def assign_material(mesh, material):
    if material.name not in mesh.materials:
        mesh.materials.append(material)
