// Long renders lose nothing: Ctrl-C (SIGINT) or SIGTERM writes the image of the passes done,
// a second Ctrl-C quits at once writing nothing, a checkpoint resumes to the very image an
// uninterrupted render gives, a checkpoint of another render is refused, and a full disk
// leaves the older files as they were.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "cli_test_util.h"
#include "film/checkpoint.h"
#include "film/image_io.h"

namespace {

using namespace clbdpt_cli_test;

const std::string kScene = std::string(CLBDPT_SCENES_DIR) + "/cornell-box/cornell-box.json";

// clbdpt with `args` in the background, its stdout and stderr into `log`. A test that fails
// before waiting for it (an ASSERT) leaves no render of a million spp running: the destructor
// kills and reaps it.
class Background {
public:
    Background(const std::string& args, const std::string& log) {
        const std::string command = "exec " + std::string(CLBDPT_BINARY) + " " + args;
        pid_ = ::fork();
        if (pid_ == 0) {
            const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            ::dup2(fd, STDOUT_FILENO);
            ::dup2(fd, STDERR_FILENO);
            ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
            ::_exit(127);
        }
    }
    Background(const Background&) = delete;
    Background& operator=(const Background&) = delete;
    ~Background() {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGKILL);
        wait_for_exit();
    }
    void signal(int sig) const { ::kill(pid_, sig); }
    // The exit status, or 128 + the signal that killed it.
    int wait_for_exit() {
        int status = 0;
        ::waitpid(pid_, &status, 0);
        pid_ = 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }

private:
    pid_t pid_ = 0;
};

bool wait_for_file(const std::string& path, double seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (fs::exists(path)) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::vector<float> read_exr(const std::string& path) {
    int w = 0, h = 0;
    return clbdpt::read_image_rgb(path, &w, &h);
}

class CheckpointTest : public CliTest {
protected:
    // No temporary file ("<name>.tmp-<pid>") left anywhere in the test's folder.
    void expect_no_temporary_files() const {
        for (const auto& entry : fs::directory_iterator(dir_))
            EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
    }
};

// Interrupted by SIGINT after a checkpoint or two: status 130, one line saying how many spp
// were written, the image and stats of exactly those; then resumed to a few more spp, the
// image equals an uninterrupted render's of that many bit for bit (same device).
TEST_F(CheckpointTest, InterruptWritesThePassesDoneAndResumeIsExact) {
    const std::string render = "render " + kScene + " --integrator bdpt --width 48 --height 48";
    Background clbdpt(render + " --spp 1000000 -o " + out("a.exr") + " --stats " + out("a.json") +
                                " --checkpoint " + out("a.ck") + " --checkpoint-every 0.1",
                            out("a.log"));
    ASSERT_TRUE(wait_for_file(out("a.ck"), 300)) << read_text(out("a.log"));
    clbdpt.signal(SIGINT);
    EXPECT_EQ(clbdpt.wait_for_exit(), 130);
    const std::string log = read_text(out("a.log"));
    std::smatch m;
    ASSERT_TRUE(std::regex_match(log, m, std::regex("clbdpt: interrupted: wrote (\\S+) with ([0-9]+) spp of 1000000; "
                                                    "checkpoint (\\S+)\n")))
        << log;
    EXPECT_EQ(m[1].str(), out("a.exr"));
    const int done = std::stoi(m[2].str());
    ASSERT_GE(done, 1);
    std::ifstream stats_file(out("a.json"));
    const nlohmann::json stats = nlohmann::json::parse(stats_file);
    EXPECT_EQ(stats["spp"], done);
    EXPECT_EQ(stats["interrupted"], true);
    EXPECT_EQ(clbdpt::read_checkpoint(out("a.ck")).film.spp, done);
    for (float v : read_exr(out("a.exr"))) ASSERT_TRUE(std::isfinite(v));
    expect_no_temporary_files();

    const std::string total = std::to_string(done + 3);
    CommandResult resumed = run(render + " --spp " + total + " -o " + out("b.exr") + " --resume " + out("a.ck") +
                                " --stats " + out("b.json"));
    ASSERT_EQ(resumed.status, 0) << resumed.output;
    // Without a checkpoint a render takes adaptive sampling's extra samples (from 8 spp on, and
    // how many depends on `done`, which the machine's load decides); a checkpointed or resumed
    // one takes none, so the uninterrupted render to compare with is one without them.
    CommandResult whole = run(render + " --spp " + total + " --adaptive off -o " + out("c.exr"));
    ASSERT_EQ(whole.status, 0) << whole.output;
    const std::vector<float> b = read_exr(out("b.exr")), c = read_exr(out("c.exr"));
    ASSERT_EQ(b.size(), c.size());
    EXPECT_EQ(std::memcmp(b.data(), c.data(), sizeof(float) * b.size()), 0) << "resumed image differs";
    std::ifstream resumed_stats_file(out("b.json"));
    const nlohmann::json resumed_stats = nlohmann::json::parse(resumed_stats_file);
    EXPECT_EQ(resumed_stats["resumed_spp"], done);
    EXPECT_EQ(resumed_stats["spp"], done + 3);
    // The resumed render went on checkpointing into the file it came from.
    EXPECT_EQ(clbdpt::read_checkpoint(out("a.ck")).film.spp, done + 3);
}

// A second Ctrl-C while the passes in flight finish ends the process at once: no image, no
// temporary file; the checkpoint written before is whole. SIGTERM stops like the first Ctrl-C.
TEST_F(CheckpointTest, SecondInterruptQuitsAtOnceAndSigtermStopsToo) {
    // Passes of 512 x 512 bdpt samples take a good part of a second on two cores: the second
    // signal arrives while one is in flight.
    Background clbdpt("render " + kScene + " --integrator bdpt --width 512 --height 512 --spp 100000 -o " +
                                out("a.exr") + " --checkpoint " + out("a.ck") + " --checkpoint-every 0.1",
                            out("a.log"));
    ASSERT_TRUE(wait_for_file(out("a.ck"), 300)) << read_text(out("a.log"));
    clbdpt.signal(SIGINT);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    clbdpt.signal(SIGINT);
    EXPECT_EQ(clbdpt.wait_for_exit(), 130);
    EXPECT_FALSE(fs::exists(out("a.exr"))) << read_text(out("a.log"));
    EXPECT_GE(clbdpt::read_checkpoint(out("a.ck")).film.spp, 1);
    expect_no_temporary_files();

    Background term("render " + kScene + " --integrator pt --width 32 --height 32 --spp 1000000 -o " +
                                 out("b.png") + " --checkpoint " + out("b.ck") + " --checkpoint-every 0.1",
                             out("b.log"));
    ASSERT_TRUE(wait_for_file(out("b.ck"), 300)) << read_text(out("b.log"));
    term.signal(SIGTERM);
    EXPECT_EQ(term.wait_for_exit(), 128 + SIGTERM);
    EXPECT_NE(read_text(out("b.log")).find("clbdpt: interrupted: wrote " + out("b.png")), std::string::npos)
        << read_text(out("b.log"));
    EXPECT_TRUE(fs::exists(out("b.png")));
}

// A checkpoint resumes only the render it came from, and only when whole.
TEST_F(CheckpointTest, ResumeRefusesAnotherRenderOrADamagedFile) {
    const std::string render = "render " + kScene + " --integrator pt --width 16 --height 16";
    CommandResult first = run(render + " --spp 4 -o " + out("a.png") + " --checkpoint " + out("a.ck"));
    ASSERT_EQ(first.status, 0) << first.output;
    const std::string bytes = read_text(out("a.ck"));
    std::ofstream(out("truncated.ck"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    std::string flipped = bytes;
    flipped[flipped.size() / 2] ^= 0x10;
    std::ofstream(out("flipped.ck"), std::ios::binary) << flipped;
    std::ofstream(out("text.ck")) << "not a checkpoint\n";
    fs::create_directories(out("inputs"));
    for (const char* name : {"truncated.ck", "flipped.ck", "text.ck"}) fs::rename(out(name), out(std::string("inputs/") + name));

    struct Case {
        const char* name;
        std::string args;
        const char* expected;
    };
    const std::string resume = " --resume " + out("a.ck");
    const Case cases[] = {
        {"other max depth", render + " --spp 8 --max-depth 3" + resume, "other settings (max_depth: 5 -> 3)"},
        {"other integrator", "render " + kScene + " --integrator bdpt --width 16 --height 16 --spp 8" + resume,
         "integrator: pt -> bdpt"},
        {"other seed", render + " --spp 8 --seed 7" + resume, "seed: 0 -> 7"},
        {"other film size", "render " + kScene + " --integrator pt --width 16 --height 15 --spp 8" + resume,
         "16x16 film"},
        {"other camera", render + " --spp 8 --fov 30" + resume, "another scene"},
        {"fewer spp than it holds", render + " --spp 2" + resume, "holds 4 spp, more than --spp 2"},
        {"truncated", render + " --spp 8 --resume " + out("inputs/truncated.ck"), "truncated"},
        {"damaged", render + " --spp 8 --resume " + out("inputs/flipped.ck"), "damaged"},
        {"not a checkpoint", render + " --spp 8 --resume " + out("inputs/text.ck"), "not a clbdpt checkpoint"},
        {"missing", render + " --spp 8 --resume " + out("inputs/none.ck"), "cannot read checkpoint"},
    };
    const std::string checkpoint_before = read_text(out("a.ck"));
    for (const Case& c : cases) {
        CommandResult r = run(c.args + " -o " + out("b.png"));
        EXPECT_EQ(r.status, 1) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find("clbdpt: error: "), std::string::npos) << c.name << ": " << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.name << ": " << r.output;
        EXPECT_EQ(r.output.find('\n', r.output.find("clbdpt: error: ")), r.output.size() - 1) << c.name;
        EXPECT_FALSE(fs::exists(out("b.png"))) << c.name;
    }
    EXPECT_EQ(read_text(out("a.ck")), checkpoint_before) << "a refused resume changed the checkpoint";
    expect_no_temporary_files();
}

// A disk that fills up while the image and the checkpoint are written (here: a file size
// limit, RLIMIT_FSIZE, with SIGXFSZ ignored so that the write fails with EFBIG): one error
// line, and the image and checkpoint of the previous render at the same paths survive intact.
TEST_F(CheckpointTest, FullDiskKeepsTheOlderFiles) {
    const std::string render = "render " + kScene + " --integrator pt --width 64 --height 64 --spp 2 -o " +
                               out("a.exr") + " --checkpoint " + out("a.ck");
    CommandResult first = run(render);
    ASSERT_EQ(first.status, 0) << first.output;
    const std::string image_before = read_text(out("a.exr")), checkpoint_before = read_text(out("a.ck"));
    ASSERT_GT(image_before.size(), 16u * 1024);  // more than the limit below allows
    const std::string limited = "ulimit -f 16; trap '' XFSZ; exec " + std::string(CLBDPT_BINARY) + " " + render +
                                " --seed 3 2>&1";
    FILE* pipe = ::popen(limited.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string output;
    char buffer[4096];
    for (size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) output.append(buffer, n);
    const int status = ::pclose(pipe);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << output;
    EXPECT_NE(output.find("clbdpt: error: cannot write '" + out("a.exr") + "'"), std::string::npos) << output;
    EXPECT_EQ(read_text(out("a.exr")), image_before);
    EXPECT_EQ(read_text(out("a.ck")), checkpoint_before);
    expect_no_temporary_files();
}

// Several devices and time budgets checkpoint too: two PoCL devices resume what they
// checkpointed and end bit for bit on one device's uninterrupted render (results are added in
// unit order whoever rendered them); a --time render resumes for --time more seconds.
TEST_F(CheckpointTest, TwoDevicesAndTimeBudgetsResume) {
    const std::string render = "render " + kScene + " --integrator bdpt --width 24 --height 24";
    const std::string two_devices = "POCL_DEVICES='pthread pthread' POCL_MAX_PTHREAD_COUNT=1 ";
    CommandResult first = run(render + " --device all --spp 4 -o " + out("a.exr") + " --checkpoint " + out("a.ck"),
                              two_devices);
    ASSERT_EQ(first.status, 0) << first.output;
    CommandResult resumed = run(render + " --device all --spp 9 -o " + out("b.exr") + " --resume " + out("a.ck") +
                                    " --stats " + out("b.json"),
                                two_devices);
    ASSERT_EQ(resumed.status, 0) << resumed.output;
    std::ifstream stats_file(out("b.json"));
    const nlohmann::json stats = nlohmann::json::parse(stats_file);
    EXPECT_EQ(stats["devices"], 2);
    EXPECT_EQ(stats["resumed_spp"], 4);
    CommandResult whole = run(render + " --spp 9 --adaptive off -o " + out("c.exr"));  // as a resume: none
    ASSERT_EQ(whole.status, 0) << whole.output;
    const std::vector<float> b = read_exr(out("b.exr")), c = read_exr(out("c.exr"));
    ASSERT_EQ(b.size(), c.size());
    ASSERT_FALSE(b.empty());
    EXPECT_EQ(std::memcmp(b.data(), c.data(), b.size() * sizeof(float)), 0);

    const std::string timed = "render " + kScene + " --integrator pt --width 16 --height 16 --time 0.3 -o " +
                              out("t.png") + " --stats " + out("t.json");
    CommandResult t1 = run(timed + " --checkpoint " + out("t.ck"));
    ASSERT_EQ(t1.status, 0) << t1.output;
    const int spp1 = clbdpt::read_checkpoint(out("t.ck")).film.spp;
    CommandResult t2 = run(timed + " --resume " + out("t.ck"));
    ASSERT_EQ(t2.status, 0) << t2.output;
    std::ifstream timed_file(out("t.json"));
    const nlohmann::json timed_stats = nlohmann::json::parse(timed_file);
    EXPECT_EQ(timed_stats["resumed_spp"], spp1);
    EXPECT_GT(timed_stats["spp"].get<int>(), spp1);
    EXPECT_EQ(clbdpt::read_checkpoint(out("t.ck")).film.spp, timed_stats["spp"].get<int>());
}

}  // namespace
