// The temporary files of Meniscus's writers, and their cleanup after a writer was killed. Every writer puts a whole
// file under a temporary name in the target's folder and renames it into place, so a killed writer (Esc on a bake
// is not a kill, but a crash, SIGKILL or a preempted farm task is) leaves the temporary file behind. Its name holds
// the writer's process id, so a later writer in the same folder can tell an abandoned file from a live one's:
//   fluid_0023.partial4711.npz         the add-on's bake (the frame pattern's extension last: listings skip it)
//   fluid_0023.npz.partial4711.meniscus a provenance record (io/provenance.h)
//   .partial-4711-surface_0023.ply     the command line's meshes (hidden on Unix; the extension chooses the format)
#pragma once
#include <string>
#include <vector>

namespace meniscus {

// A temporary file of a writer on another machine that shares the folder has a process id this machine cannot check:
// it is removed only once untouched for this long (writing a mesh takes seconds).
constexpr double kAbandonedPartialSeconds = 600;

// The temporary name for writing `target` (a path) in process process_id: "<stem>.partial<id><extension>" where the
// extension is the last one of target's name, so that the format stays recognisable and frame patterns skip it.
std::string partial_path(const std::string& target, long process_id);
// The command line's temporary name for writing `target`: ".partial-<id>-<name>" in target's folder (hidden on Unix;
// the extension, which chooses the format, stays last).
std::string hidden_partial_path(const std::string& target, long process_id);
// The process id in a temporary file's name (either form above); -1 for any other name.
long partial_writer(const std::string& file_name);
// Removes the temporary files in folder whose writer is gone (no such process here) and that were untouched for
// abandoned_after_seconds; returns their names. Files of live writers and all other files stay; errors are ignored
// (a folder that cannot be listed has nothing to clean).
std::vector<std::string> remove_abandoned_partials(const std::string& folder,
                                                   double abandoned_after_seconds = kAbandonedPartialSeconds);

}  // namespace meniscus
