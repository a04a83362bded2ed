// Ctrl-C and SIGTERM during a render: the first asks the render to stop after the passes in
// flight (the command line then writes what it has); the second ends the process at once, with
// status 128 + signal, writing nothing and removing any output file it was half-way through.
#pragma once

namespace clbdpt {

void install_interrupt_handlers();

// The signal that asked the render to stop (SIGINT or SIGTERM), 0 if none has.
int interrupt_signal();

}  // namespace clbdpt
