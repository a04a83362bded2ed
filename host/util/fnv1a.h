// 64-bit FNV-1a: a fast, non-cryptographic hash that tells an accidental change (a damaged
// file, another scene) from the same bytes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace clbdpt {

class Fnv1a {
public:
    void bytes(const void* data, size_t size) {
        const unsigned char* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < size; ++i) {
            hash_ ^= p[i];
            hash_ *= 1099511628211ull;
        }
    }
    // The size first, so that neighbouring arrays cannot trade elements unnoticed.
    template <typename T>
    void array(const std::vector<T>& v) {
        const uint64_t n = v.size();
        bytes(&n, sizeof n);
        bytes(v.data(), sizeof(T) * v.size());
    }
    uint64_t value() const { return hash_; }

private:
    uint64_t hash_ = 14695981039346656037ull;
};

}  // namespace clbdpt
