// A cap on the size of single allocations, for reading files whose parsers trust the sizes the
// file states. OpenVDB allocates whatever a length field says: fuzzing found a damaged 10 KB
// .vdb file that made clbdpt allocate 12 GiB (and take 23 s) before OpenVDB noticed the damage;
// on a smaller machine that is a crash. While an AllocationCap is alive, any single `new` larger
// than the cap throws std::bad_alloc instead, which the reader reports as a damaged file.
//
// The cap is process-wide (OpenVDB may read on TBB's threads); scenes are loaded before any
// render thread exists, so nothing else allocates meanwhile. It applies to allocations through
// operator new, which this file's implementation replaces program-wide (plain malloc/free
// underneath, so sanitizers see matching pairs).
#pragma once

#include <cstddef>

namespace clbdpt {

class AllocationCap {
public:
    explicit AllocationCap(size_t max_bytes);
    ~AllocationCap();
    AllocationCap(const AllocationCap&) = delete;
    AllocationCap& operator=(const AllocationCap&) = delete;

private:
    size_t previous_;
};

}  // namespace clbdpt
