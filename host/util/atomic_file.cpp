#include "util/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "util/error.h"

namespace clbdpt {

namespace {

// Names of the temporary files that exist now, in static memory a signal handler may read: a
// slot is claimed by setting its flag, then filled, then published; the handler only reads
// published slots. Longer names than a slot holds are simply not registered (the RAII removal
// still covers them on every path but an immediate exit).
constexpr int kSlots = 16;
constexpr size_t kSlotBytes = 4096;
char g_names[kSlots][kSlotBytes];
std::atomic<int> g_state[kSlots];  // 0 free, 1 being written, 2 published

int register_name(const std::string& name) {
    if (name.size() >= kSlotBytes) return -1;
    for (int i = 0; i < kSlots; ++i) {
        int expected = 0;
        if (g_state[i].compare_exchange_strong(expected, 1)) {
            std::memcpy(g_names[i], name.c_str(), name.size() + 1);
            g_state[i].store(2);
            return i;
        }
    }
    return -1;
}

void unregister_name(int slot) {
    if (slot >= 0) g_state[slot].store(0);
}

std::string folder_of(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
}

}  // namespace

TemporaryFile::TemporaryFile(const std::string& target)
    : target_(target), path_(target + ".tmp-" + std::to_string(static_cast<long>(::getpid()))) {
    slot_ = register_name(path_);
}

TemporaryFile::~TemporaryFile() {
    unregister_name(slot_);
    if (!path_.empty()) std::remove(path_.c_str());
}

void TemporaryFile::commit(bool durable) {
    auto fail = [&](const char* what) {
        throw Error("cannot write '" + target_ + "': " + what + ": " + std::strerror(errno));
    };
    if (durable) {
        const int fd = ::open(path_.c_str(), O_RDONLY);
        if (fd < 0) fail("open");
        const int synced = ::fsync(fd);
        ::close(fd);
        if (synced != 0) fail("fsync");
    }
    if (std::rename(path_.c_str(), target_.c_str()) != 0) fail("rename");
    unregister_name(slot_);
    slot_ = -1;
    path_.clear();
    if (durable) {
        // The rename itself reaches the disk with the folder's metadata.
        const int dir = ::open(folder_of(target_).c_str(), O_RDONLY | O_DIRECTORY);
        if (dir >= 0) {
            ::fsync(dir);
            ::close(dir);
        }
    }
}

void check_can_write(const std::string& path) {
    TemporaryFile temp(path);
    const int fd = ::open(temp.path().c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd < 0) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    ::close(fd);
}

void write_file_atomically(const std::string& path, const std::string& bytes, bool durable) {
    TemporaryFile temp(path);
    std::FILE* f = std::fopen(temp.path().c_str(), "wb");
    if (!f) throw Error("cannot write '" + path + "': " + std::strerror(errno));
    const bool written = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    const int saved_errno = errno;
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed)
        throw Error("cannot write '" + path + "': " + std::strerror(written ? errno : saved_errno));
    temp.commit(durable);
}

void remove_temporary_files_from_signal_handler() {
    for (int i = 0; i < kSlots; ++i)
        if (g_state[i].load() == 2) ::unlink(g_names[i]);
}

}  // namespace clbdpt
