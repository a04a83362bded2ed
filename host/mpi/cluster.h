// The processes of one render started by `mpirun -n N clbdpt render ...` (Open MPI; the build
// has it when libopenmpi-dev is installed). Process 0, the leader, loads the scene like the
// others, runs the strategy pilot and the checkpoint, shares out the work units to every
// process's devices as to its own (render/unit_queue.h: by measured rate, with take-over at the
// end), adds the results in unit order and alone writes the image and the summary. The image is
// therefore the one a single process renders, bit for bit on identical devices.
//
// Without mpirun (or without MPI in the build) this is one process and every call is trivial.
// A process that dies ends the whole job through MPI's own error handling (mpirun's message),
// and a process that fails with an error ends it through MPI_Abort after printing its line.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/render_loop.h"

namespace clbdpt {

// What the leader decides for every process before the kernels are built.
struct RenderPlan {
    int integrator = 0;
    float light_subpaths = 1.0f;
    int inner_connections = 1;
    int roulette_light_from = kRouletteOff;
};

class Cluster {
public:
    // Joins the MPI job when the process was started by mpirun.
    Cluster(int* argc, char*** argv);
    ~Cluster();
    Cluster(const Cluster&) = delete;
    Cluster& operator=(const Cluster&) = delete;

    int rank() const { return rank_; }
    int size() const { return size_; }
    bool leader() const { return rank_ == 0; }

    // The leader's plan, to every process (the others wait for it).
    void share_plan(RenderPlan* plan);
    // Leader: one worker per device of every other process. Each process's scene must have the
    // leader's fingerprint (the same files on every machine), else this throws.
    std::vector<std::unique_ptr<UnitWorker>> connect_remote_devices(uint64_t scene_fingerprint, int width,
                                                                    int height);
    // Leader: tells every other process that the render is over.
    void release_remote_devices();
    // The others: announce their devices, then render what the leader sends until it says stop.
    void serve(const std::vector<Renderer*>& renderers, uint64_t scene_fingerprint);
    // Ends every process of the job (after this one printed its error line).
    [[noreturn]] void abort(int status);

    // Tests only: this process ends abruptly (as if killed) after rendering `runs` runs.
    int debug_exit_after_runs = -1;

private:
    int rank_ = 0;
    int size_ = 1;
    bool joined_ = false;
    std::vector<int> remote_device_counts_;  // leader: devices of each process
};

}  // namespace clbdpt
