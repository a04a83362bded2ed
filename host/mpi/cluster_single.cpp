// The build without MPI: always one process.
#include <cstdio>
#include <cstdlib>

#include "mpi/cluster.h"

namespace clbdpt {

Cluster::Cluster(int*, char***) {
    // Under mpirun every process would render the whole image alone and write the same file.
    const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
    if (size && std::atoi(size) > 1) {
        std::fprintf(stderr, "clbdpt: error: this clbdpt was built without MPI and cannot share a render under mpirun "
                             "(install libopenmpi-dev and build again)\n");
        std::exit(1);
    }
}
Cluster::~Cluster() = default;
void Cluster::share_plan(RenderPlan*) {}
std::vector<std::unique_ptr<UnitWorker>> Cluster::connect_remote_devices(uint64_t, int, int) { return {}; }
void Cluster::release_remote_devices() {}
void Cluster::serve(const std::vector<Renderer*>&, uint64_t) {}
void Cluster::abort(int status) { std::exit(status); }

}  // namespace clbdpt
