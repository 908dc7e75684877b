"""A surface's '//' paths (particle files, cache files) follow the .blend as Blender's own relative paths do.

Blender rewrites its own '//' paths when Save As puts the .blend in another folder; the add-on's properties are not
among them. So each surface records the folder its '//' paths are relative to (`paths_folder`, written at every
save), and they are rewritten here:
- Save As / Save Copy: where Blender says where the file goes (4.x and 5.x: save_pre's argument), before it is
  written (a copy gets the rewritten paths, the open file keeps its own, and so does a save that fails);
- Save As where it does not (3.4): in memory right after the save; the file written keeps the old folder, which
  the next load sees;
- opening a .blend from another folder than its paths were written for: each '//' path that does not resolve
  beside the .blend (it was moved without its files, or saved elsewhere by 3.4) is rewritten to point where it
  pointed from the recorded folder; one that resolves (moved with its files) is kept;
- undo and redo: a step from before a Save As restores paths written for the old folder; they are rebased too.
Values are written as ID properties, not through the settings: the paths point at the same files, so nothing has to
be rebuilt, and no update callback runs inside Blender's save.
"""
import os

import bpy

from .. import cache

PATH_PROPERTIES = ("file_pattern", "cache_pattern")
FOLDER_PROPERTY = "paths_folder"
# 4.5 and later warn when a '//' path is stored in a path property not declared to accept one.
BLEND_RELATIVE_OPTIONS = {"PATH_SUPPORTS_BLEND_RELATIVE"} if bpy.app.version >= (4, 5, 0) else set()

# Values replaced for a Save As / Save Copy, put back after a copy or a failed save: object name -> {property: value}.
_before_copy = {}


def blend_folder(filepath):
    return os.path.dirname(os.path.abspath(filepath)) if filepath else ""


def rebased(stored, old_folder, new_folder):
    """The '//' path stored relative to old_folder, relative to new_folder (absolute where no relative path exists,
    e.g. another drive); None when it needs no change."""
    if not stored.startswith("//") or not old_folder or not new_folder or \
            os.path.normcase(old_folder) == os.path.normcase(new_folder):
        return None
    target = os.path.normpath(os.path.join(old_folder, stored[2:]))
    try:
        return bpy.path.relpath(target, start=new_folder)
    except ValueError:
        return target


def _baked_default(name, settings, folder):
    """An empty Cache Files means the default folder beside the .blend; once a bake is there, the surface's frames
    are, so it follows the .blend as an explicit path would (its '//' form; empty while nothing is baked)."""
    default = cache.default_cache_pattern(name, settings.cache_format)
    return default if folder and os.path.isdir(os.path.dirname(os.path.join(folder, default[2:]))) else ""


def _surface_settings():
    for obj in bpy.data.objects:
        if obj.type == "MESH" and obj.library is None and obj.meniscus.is_surface:
            yield obj.name, obj.meniscus


def _rebase_all(old_folder, new_folder, keep_resolving=False):
    """Rewrites every surface's '//' paths from old_folder to new_folder; with keep_resolving, a path whose folder
    exists beside new_folder is kept. Returns {object name: {property: value before}} (the folder too)."""
    changed = {}
    for name, settings in _surface_settings():
        folder = settings.get(FOLDER_PROPERTY) or old_folder
        before = {FOLDER_PROPERTY: settings.get(FOLDER_PROPERTY, "")}
        for prop in PATH_PROPERTIES:
            stored = getattr(settings, prop)
            if not stored and prop == "cache_pattern":
                stored = _baked_default(name, settings, folder)
            new = rebased(stored, folder, new_folder)
            if new is None:
                continue
            if keep_resolving and os.path.isdir(os.path.dirname(os.path.join(new_folder, stored[2:]))):
                continue
            before[prop] = getattr(settings, prop)
            settings[prop] = new
        if settings.get(FOLDER_PROPERTY) != new_folder:  # unchanged values are not written (undo calls this too)
            settings[FOLDER_PROPERTY] = new_folder
        changed[name] = before
    return changed


def before_save(filepath=None):
    """save_pre: filepath is where the file goes (None on 3.4)."""
    _before_copy.clear()
    current = blend_folder(bpy.data.filepath)
    target = blend_folder(filepath) if isinstance(filepath, str) and filepath else ""
    if target and current:
        _before_copy.update(_rebase_all(current, target))
    elif target or current:  # the folder these paths are relative to, in the file written
        for _, settings in _surface_settings():
            settings[FOLDER_PROPERTY] = target or current


def after_save(filepath=None):
    """save_post: after Save Copy the open file keeps its own paths; after 3.4's Save As they follow it now."""
    current = blend_folder(bpy.data.filepath)
    target = blend_folder(filepath) if isinstance(filepath, str) and filepath else ""
    if target and os.path.normcase(target) != os.path.normcase(current):  # a copy: put the open file's back
        _restore_before_save()
    _before_copy.clear()
    if not target and current:
        _rebase_all(current, current)  # each surface from its recorded folder to the file's new one


def after_failed_save(filepath=None):
    """save_post_fail (4.2+; save_post does not run): nothing was written and the open file stays where it was, so
    it keeps the paths it had before save_pre rewrote them."""
    _restore_before_save()
    _before_copy.clear()


def after_undo():
    """undo_post / redo_post: undo restores the paths as its step stored them, possibly for the folder the .blend
    was in before a Save As since; each is rebased from its recorded folder to the file's."""
    current = blend_folder(bpy.data.filepath)
    if current:
        _rebase_all(current, current)


def _restore_before_save():
    for name, values in _before_copy.items():
        obj = bpy.data.objects.get(name)
        if obj is not None:
            for prop, value in values.items():
                obj.meniscus[prop] = value


def after_load():
    """load_post: paths written for another folder than the .blend's now."""
    current = blend_folder(bpy.data.filepath)
    if current:
        _rebase_all(current, current, keep_resolving=True)
