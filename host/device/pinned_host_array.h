// Host memory that read-backs land in, allocated by the OpenCL driver (CL_MEM_ALLOC_HOST_PTR)
// and kept mapped while the array lives. GPU drivers hand out pinned pages, which their copy
// engines fill directly; a read into ordinary (pageable) memory goes through a staging copy at
// about a third of the speed (NVIDIA's OpenCL best-practice guide; docs/throughput.md has the
// figures measured here). On PoCL the buffer is plain host memory and nothing changes.
#pragma once

#include <CL/opencl.hpp>

#include <cstddef>
#include <utility>

namespace clbdpt {

template <typename T>
class PinnedHostArray {
public:
    PinnedHostArray() = default;
    // Throws cl::Error if the driver cannot allocate or map it.
    PinnedHostArray(const cl::Context& context, const cl::CommandQueue& queue, size_t count) : size_(count) {
        if (count == 0) return;
        queue_ = queue;
        buffer_ = cl::Buffer(context, CL_MEM_ALLOC_HOST_PTR | CL_MEM_READ_WRITE, sizeof(T) * count);
        data_ = static_cast<T*>(
            queue_.enqueueMapBuffer(buffer_, CL_TRUE, CL_MAP_READ | CL_MAP_WRITE, 0, sizeof(T) * count));
    }
    PinnedHostArray(const PinnedHostArray&) = delete;
    PinnedHostArray& operator=(const PinnedHostArray&) = delete;
    PinnedHostArray(PinnedHostArray&& other) noexcept { swap(other); }
    PinnedHostArray& operator=(PinnedHostArray&& other) noexcept {
        PinnedHostArray(std::move(other)).swap(*this);
        return *this;
    }
    ~PinnedHostArray() {
        if (!data_) return;
        try {
            queue_.enqueueUnmapMemObject(buffer_, data_);
            queue_.finish();
        } catch (const cl::Error&) {
            // The device is gone (a failed render): the driver frees the buffer with it.
        }
    }

    T* data() const { return data_; }
    T& operator[](size_t i) const { return data_[i]; }
    size_t size() const { return size_; }

private:
    void swap(PinnedHostArray& other) noexcept {
        std::swap(buffer_, other.buffer_);
        std::swap(queue_, other.queue_);
        std::swap(data_, other.data_);
        std::swap(size_, other.size_);
    }

    cl::Buffer buffer_;
    cl::CommandQueue queue_;
    T* data_ = nullptr;
    size_t size_ = 0;
};

}  // namespace clbdpt
