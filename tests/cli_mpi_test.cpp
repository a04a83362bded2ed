// `mpirun -n N clbdpt render ...` (mpi/cluster.h), run here with Open MPI on this machine's one
// node (--oversubscribe: more processes than cores). Every process renders on PoCL; the leader
// writes the image, which must equal a single process's bit for bit, also across a checkpoint
// written by one number of processes and resumed by another. A process that dies ends the job
// with an error instead of a hang. Only in builds with MPI (the README's test command installs
// it, so CI runs these).
#ifdef CLBDPT_HAS_MPI

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_test_util.h"
#include "device/opencl.h"
#include "film/image_io.h"

namespace {

using namespace clbdpt_cli_test;

// Where /sys is not mounted (a bare chroot such as the fresh-machine check), mpirun's hwloc
// loads PoCL through its OpenCL plugin, PoCL finds no memory and aborts mpirun before clbdpt
// starts (clbdpt's own remedy, device/opencl.cpp, comes too late). The README's advice for that
// case: describe the machine to hwloc, which every process then inherits.
std::string hwloc_without_sysfs() {
    const std::string topology = clbdpt::hwloc_topology_without_sysfs();
    return topology.empty() ? "" : "HWLOC_COMPONENTS=synthetic HWLOC_SYNTHETIC='" + topology + "' ";
}

// Under scripts/sanitize.sh (AddressSanitizer): Open MPI's plugins keep allocations until exit
// and are unloaded by then, so LeakSanitizer's fast unwinder stops at frames without a module
// name; the full unwinder reaches the libmpi frames that scripts/lsan.supp names (and makes
// these tests about seven times slower, so only here).
#if defined(__SANITIZE_ADDRESS__)
const char* const kSanitizerOptions = "ASAN_OPTIONS=\"$ASAN_OPTIONS:fast_unwind_on_malloc=0\" ";
#else
const char* const kSanitizerOptions = "";
#endif

// Root may run mpirun here (containers, CI); PoCL on one thread per process keeps three
// processes on two cores fair. `timeout` turns a hang into a failure.
std::string mpirun(int processes) {
    return hwloc_without_sysfs() + kSanitizerOptions +
           "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
           "POCL_MAX_PTHREAD_COUNT=1 timeout 300 mpirun --oversubscribe -n " +
           std::to_string(processes) + " ";
}

const std::string kRender = "render " + std::string(CLBDPT_SCENES_DIR) +
                            "/cornell-box/cornell-box.json --integrator bdpt --width 80 --height 64";

nlohmann::json read_json(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

TEST_F(CliTest, MpiProcessesRenderTheSingleProcessImage) {
    CommandResult one = run(kRender + " --spp 5 -o " + out("one.exr"));
    ASSERT_EQ(one.status, 0) << one.output;
    for (int processes : {2, 3}) {
        const std::string image = out("mpi" + std::to_string(processes) + ".exr");
        const std::string stats = out("mpi" + std::to_string(processes) + ".json");
        CommandResult r = run(kRender + " --spp 5 -o " + image + " --stats " + stats, mpirun(processes));
        ASSERT_EQ(r.status, 0) << r.output;
        expect_same_image(out("one.exr"), image);
        const nlohmann::json j = read_json(stats);
        EXPECT_EQ(j["processes"], processes);
        ASSERT_EQ(j["device_shares"].size(), size_t(processes)) << j.dump(2);
        uint64_t samples = 0;
        for (const nlohmann::json& d : j["device_shares"]) samples += d["samples"].get<uint64_t>();
        EXPECT_EQ(samples, 5u * 80 * 64);
        // One summary, from the leader.
        size_t lines = 0;
        for (size_t at = 0; (at = r.output.find(" spp 80x64 in ", at)) != std::string::npos; ++at) ++lines;
        EXPECT_EQ(lines, 1u) << r.output;
    }
}

// A small film and many passes: each process's device soon takes runs of several passes and
// renders them in one go (DeviceWorker); the leader accepts those joined results and the image
// is still the single process's (adaptive sampling, off under MPI, is off in both).
TEST_F(CliTest, MpiDevicesJoinPassesIntoOneRun) {
    const std::string render = "render " + std::string(CLBDPT_SCENES_DIR) +
                               "/cornell-box/cornell-box.json --integrator bdpt --width 16 --height 12 --spp 64 "
                               "--adaptive off";
    CommandResult one = run(render + " -o " + out("one.exr"));
    ASSERT_EQ(one.status, 0) << one.output;
    CommandResult r = run(render + " -o " + out("two.exr"), mpirun(2));
    ASSERT_EQ(r.status, 0) << r.output;
    // A result the leader refuses drops that process's device, and the leader renders on alone.
    EXPECT_EQ(r.output.find("warning"), std::string::npos) << r.output;
    expect_same_image(out("one.exr"), out("two.exr"));
}

TEST_F(CliTest, MpiCheckpointResumesUnderAnotherProcessCount) {
    CommandResult first = run(kRender + " --spp 3 -o " + out("a.exr") + " --checkpoint " + out("a.ck"), mpirun(2));
    ASSERT_EQ(first.status, 0) << first.output;
    CommandResult resumed = run(kRender + " --spp 7 -o " + out("b.exr") + " --resume " + out("a.ck") + " --stats " +
                                    out("b.json"),
                                mpirun(3));
    ASSERT_EQ(resumed.status, 0) << resumed.output;
    EXPECT_EQ(read_json(out("b.json"))["resumed_spp"], 3);
    CommandResult whole = run(kRender + " --spp 7 -o " + out("c.exr"));
    ASSERT_EQ(whole.status, 0) << whole.output;
    expect_same_image(out("b.exr"), out("c.exr"));
}

// Each process has two devices, and in each the second fails after three launches: the
// leader drops its own and the other process's failed device (whose error comes back as its
// answer) with one warning each, gives their runs to the two devices left, and the image is
// still the single process's bit for bit.
TEST_F(CliTest, MpiDevicesThatFailLoseNothing) {
    CommandResult one = run(kRender + " --spp 4 -o " + out("one.exr"));
    ASSERT_EQ(one.status, 0) << one.output;
    CommandResult r = run(kRender + " --spp 4 --device all --batch-items 1024 --debug-fail-device 1:3 -o " +
                              out("two.exr") + " --stats " + out("two.json"),
                          "POCL_DEVICES='pthread basic' " + mpirun(2));
    ASSERT_EQ(r.status, 0) << r.output;
    const nlohmann::json j = read_json(out("two.json"));
    ASSERT_EQ(j["dropped_devices"].size(), 2u) << j.dump(2);
    int remote = 0;
    for (const nlohmann::json& d : j["dropped_devices"])
        remote += d.get<std::string>().find("(process 1): ") != std::string::npos ? 1 : 0;
    EXPECT_EQ(remote, 1) << j.dump(2);
    EXPECT_EQ(j["samples"], 4u * 80 * 64);
    expect_same_image(out("one.exr"), out("two.exr"));
}

// Process 1 ends abruptly after its first run (as if its machine went down): mpirun ends the
// job with a non-zero status and its own message, within the timeout, and no image is written.
TEST_F(CliTest, MpiProcessThatDiesFailsTheRun) {
    CommandResult r = run(kRender + " --spp 50 -o " + out("x.exr") + " --debug-exit-process 1:1", mpirun(2));
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_NE(r.status, 124) << "timed out: the job hung\n" << r.output;
    EXPECT_NE(r.output.find("process 1 ends abruptly"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out("x.exr")));
}

// An error in one process (here the leader's: an output folder that does not exist) ends every
// process with the error line, not a hang.
TEST_F(CliTest, MpiErrorInOneProcessEndsTheJob) {
    CommandResult r = run(kRender + " --spp 2 -o " + out("missing/x.exr"), mpirun(2));
    EXPECT_NE(r.status, 0) << r.output;
    EXPECT_NE(r.status, 124) << "timed out: the job hung\n" << r.output;
    EXPECT_NE(r.output.find("clbdpt: error: cannot write"), std::string::npos) << r.output;
}

}  // namespace

#endif  // CLBDPT_HAS_MPI
