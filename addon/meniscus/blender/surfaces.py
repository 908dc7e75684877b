"""Surface objects: what makes an object a Meniscus surface (operators.add_surface_object adds them)."""
STATUS_LINE_SEPARATOR = "\n"  # the status holds one fact per line; the panel shows each on its own row


def is_surface(obj):
    return obj is not None and obj.type == "MESH" and obj.meniscus.is_surface


def surface_objects(scene):
    return [obj for obj in scene.objects if is_surface(obj)]
