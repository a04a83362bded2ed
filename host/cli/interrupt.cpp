#include "cli/interrupt.h"

#include <unistd.h>

#include <atomic>
#include <csignal>

#include "util/atomic_file.h"

namespace clbdpt {

namespace {

std::atomic<int> g_signal{0};
// Someone pressed Ctrl-C at a terminal: tell them at once that it was heard (the line saying
// what was saved comes at the end either way).
bool g_acknowledge = false;
static_assert(std::atomic<int>::is_always_lock_free, "read and written by a signal handler");

void on_signal(int sig) {
    int none = 0;
    if (g_signal.compare_exchange_strong(none, sig)) {
        if (!g_acknowledge) return;
        static const char kMessage[] =
            "\nclbdpt: interrupted: finishing the passes in flight, then writing the image (again to quit at once)\n";
        const ssize_t ignored = ::write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
        (void)ignored;
        return;
    }
    remove_temporary_files_from_signal_handler();
    ::_exit(128 + sig);
}

}  // namespace

void install_interrupt_handlers() {
    g_acknowledge = ::isatty(STDERR_FILENO) != 0;
    struct sigaction action {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    // Restart interrupted system calls: the render's threads should not see EINTR.
    action.sa_flags = SA_RESTART;
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
}

int interrupt_signal() { return g_signal.load(); }

}  // namespace clbdpt
