// Output files appear whole or not at all: each is written to "<path>.tmp-<pid>" beside its
// target and renamed over it at the end (atomic within a folder), so a failed write, a full
// disk or an interrupt leaves an older file at the same path as it was.
#pragma once

#include <string>

namespace clbdpt {

// A temporary file beside `target`, removed when this goes out of scope unless commit() renamed
// it over the target. While it exists its name is registered so that a signal handler can
// remove it too (remove_temporary_files_from_signal_handler), e.g. on a second Ctrl-C.
class TemporaryFile {
public:
    explicit TemporaryFile(const std::string& target);
    ~TemporaryFile();
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;

    const std::string& path() const { return path_; }
    // Renames the temporary file over the target; with durable, first flushes it to the disk
    // (fsync) and afterwards the folder's entry, so a crash of the machine cannot leave an empty
    // or partial file under the target's name. Throws Error naming the target.
    void commit(bool durable = false);

private:
    std::string target_, path_;
    int slot_ = -1;  // in the signal-safe registry
};

// Throws Error naming `path` unless a file can be created beside it (the folder exists and is
// writable): checked before a render, so an hour of work is not lost to a typo in -o.
void check_can_write(const std::string& path);

// Writes `bytes` to `path` through a TemporaryFile. Throws Error naming the path.
void write_file_atomically(const std::string& path, const std::string& bytes, bool durable = false);

// Unlinks every registered temporary file. Async-signal-safe: only unlink(2) on names stored
// in static memory.
void remove_temporary_files_from_signal_handler();

}  // namespace clbdpt
