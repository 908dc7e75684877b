// The thread count of a frame whose user chose none: the cores other programs leave free when it starts.
#pragma once

namespace meniscus {

// Threads for one frame with the automatic count (threads 0): the cores this process may use, less those that other
// programs keep busy at this moment (Linux: the machine's running threads, sampled a few times over a fraction of a
// millisecond; elsewhere, or when that cannot be read, every core). At least 1. Beside programs that hold cores, a
// frame on all cores makes its threads wait at every barrier for one the scheduler has set aside (a frame of the
// default pipeline took 3.3x its idle time beside two busy loops on 2 cores); the mesh is the same for any count.
int automatic_frame_threads();

// The rule behind it: of `usable` cores (this process's), `online` on the machine, with `busy_elsewhere` threads
// running for other programs spread evenly over them, the whole cores left, capped at `most` threads, at least 1.
int free_cores(int most, int usable, int online, int busy_elsewhere);

// This process's threads running or ready to run, the caller among them (Linux; 0 elsewhere or when unreadable): the
// machine's count less these is what other programs hold, so the core's own OpenMP threads still spinning after a
// parallel region, or the host's (Blender's) busy threads, never take a frame's cores away.
int own_running_threads();

}  // namespace meniscus
