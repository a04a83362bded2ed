#include "mpi/items_message.h"

#include <cstring>
#include <type_traits>

#include "util/error.h"

namespace clbdpt {

namespace {

constexpr uint8_t kResults = 1, kFailure = 2;

class Writer {
public:
    template <typename T>
    void put(const T& value) {
        static_assert(std::is_trivially_copyable<T>::value, "plain values only");
        const auto* p = reinterpret_cast<const uint8_t*>(&value);
        bytes.insert(bytes.end(), p, p + sizeof(T));
    }
    template <typename T>
    void put_vector(const std::vector<T>& v) {
        put(uint64_t(v.size()));
        const auto* p = reinterpret_cast<const uint8_t*>(v.data());
        bytes.insert(bytes.end(), p, p + v.size() * sizeof(T));
    }
    std::vector<uint8_t> bytes;
};

class Reader {
public:
    explicit Reader(const std::vector<uint8_t>& b) : bytes_(b) {}
    template <typename T>
    T get() {
        T value;
        need(sizeof(T));
        std::memcpy(&value, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    template <typename T>
    std::vector<T> get_vector() {
        const uint64_t n = get<uint64_t>();
        if (n > (bytes_.size() - at_) / sizeof(T)) damaged();
        std::vector<T> v(static_cast<size_t>(n));
        if (n > 0) std::memcpy(v.data(), bytes_.data() + at_, size_t(n) * sizeof(T));
        at_ += size_t(n) * sizeof(T);
        return v;
    }
    bool at_end() const { return at_ == bytes_.size(); }
    [[noreturn]] static void damaged() { throw Error("MPI: a damaged message from another process"); }

private:
    void need(size_t n) const {
        if (bytes_.size() - at_ < n) damaged();
    }
    const std::vector<uint8_t>& bytes_;
    size_t at_ = 0;
};

}  // namespace

std::vector<uint8_t> encode_runs(const std::vector<ItemRun>& runs) {
    Writer w;
    w.put_vector(runs);
    return w.bytes;
}

std::vector<ItemRun> decode_runs(const std::vector<uint8_t>& bytes) {
    Reader r(bytes);
    std::vector<ItemRun> runs = r.get_vector<ItemRun>();
    if (!r.at_end()) Reader::damaged();
    return runs;
}

std::vector<uint8_t> encode_results(const std::vector<RenderedItems>& results) {
    Writer w;
    w.put(kResults);
    w.put(uint64_t(results.size()));
    for (const RenderedItems& items : results) {
        w.put(items.sample_index);
        w.put(items.first_item);
        w.put(items.item_count);
        w.put(items.pixel_stride);
        w.put(items.run_pixel);
        w.put(items.run_length);
        w.put(items.strategy_slots);
        w.put(items.strategy_stride);
        w.put_vector(items.camera);
        w.put_vector(items.dropped_items);
        w.put_vector(items.splats);
        w.put_vector(items.strategy_splats);
        w.put(items.counts.samples);
        w.put(items.counts.rays);
        w.put(items.counts.dropped_samples);
        w.put_vector(items.counts.first_dropped);
    }
    return w.bytes;
}

std::vector<uint8_t> encode_failure(const std::string& what) {
    Writer w;
    w.put(kFailure);
    w.put_vector(std::vector<char>(what.begin(), what.end()));
    return w.bytes;
}

std::vector<RenderedItems> decode_results(const std::vector<uint8_t>& bytes) {
    Reader r(bytes);
    const uint8_t kind = r.get<uint8_t>();
    if (kind == kFailure) {
        const std::vector<char> what = r.get_vector<char>();
        throw Error(std::string(what.begin(), what.end()));
    }
    if (kind != kResults) Reader::damaged();
    const uint64_t n = r.get<uint64_t>();
    std::vector<RenderedItems> results;
    for (uint64_t k = 0; k < n; ++k) {
        RenderedItems items;
        items.sample_index = r.get<uint32_t>();
        items.first_item = r.get<int>();
        items.item_count = r.get<int>();
        items.pixel_stride = r.get<int>();
        items.run_pixel = r.get<int>();
        items.run_length = r.get<int>();
        items.strategy_slots = r.get<int>();
        items.strategy_stride = r.get<int>();
        items.camera = r.get_vector<float>();
        items.dropped_items = r.get_vector<int>();
        items.splats = r.get_vector<SplatRecord>();
        items.strategy_splats = r.get_vector<RenderedItems::StrategySplat>();
        items.counts.samples = r.get<uint64_t>();
        items.counts.rays = r.get<uint64_t>();
        items.counts.dropped_samples = r.get<uint64_t>();
        items.counts.first_dropped = r.get_vector<DroppedSample>();
        if (items.item_count < 0 || items.camera.size() != size_t(items.item_count) * 3) Reader::damaged();
        results.push_back(std::move(items));
    }
    if (!r.at_end()) Reader::damaged();
    return results;
}

bool results_match_runs(const std::vector<ItemRun>& runs, const std::vector<RenderedItems>& results, int pixels) {
    size_t k = 0;
    for (const RenderedItems& r : results) {
        if (k >= runs.size() || r.sample_index != runs[k].pass || r.first_item != runs[k].first_item ||
            r.pixel_stride != 1)
            return false;
        if (r.run_length == 0) {
            if (r.item_count != runs[k].item_count) return false;
            ++k;
        } else {
            int64_t items = 0;
            const size_t n = joinable_runs(runs, k, pixels, r.item_count, &items);
            if (r.run_pixel != 0 || r.run_length != pixels || n < 2 || items != r.item_count) return false;
            k += n;
        }
        for (const SplatRecord& s : r.splats)
            if (s.pixel < 0 || s.pixel >= pixels) return false;
        for (const RenderedItems::StrategySplat& s : r.strategy_splats)
            if (s.splat.pixel < 0 || s.splat.pixel >= pixels || s.slot < 0 || s.slot >= r.strategy_slots) return false;
    }
    return k == runs.size();
}

}  // namespace clbdpt
