// buffer_pool.cpp — device buffers kept between builds.
#include "cl/runtime/buffer_pool.h"

#include <utility>

namespace kdray {

cl::Buffer BufferPool::take(std::size_t bytes, std::size_t limit, std::size_t* taken_bytes) {
    auto best = kept_.end();
    for (auto it = kept_.begin(); it != kept_.end(); ++it)
        if (it->bytes >= bytes && it->bytes <= limit &&
            (best == kept_.end() || it->bytes < best->bytes))
            best = it;
    if (best == kept_.end()) return cl::Buffer();
    cl::Buffer buffer = std::move(best->buffer);
    *taken_bytes = best->bytes;
    bytes_ -= best->bytes;
    kept_.erase(best);
    return buffer;
}

void BufferPool::keep(cl::Buffer buffer, std::size_t bytes) {
    if (bytes > capacity_) return;
    kept_.push_back({bytes, std::move(buffer)});
    bytes_ += bytes;
    while (bytes_ > capacity_) {
        bytes_ -= kept_.front().bytes;
        kept_.erase(kept_.begin());
    }
}

std::size_t BufferPool::release_oldest() {
    if (kept_.empty()) return 0;
    const std::size_t bytes = kept_.front().bytes;
    bytes_ -= bytes;
    kept_.erase(kept_.begin());
    return bytes;
}

std::size_t BufferPool::move_oldest_into(BufferPool& other) {
    if (kept_.empty()) return 0;
    Kept oldest = std::move(kept_.front());
    kept_.erase(kept_.begin());
    bytes_ -= oldest.bytes;
    other.keep(std::move(oldest.buffer), oldest.bytes);
    return oldest.bytes;
}

void BufferPool::move_into(BufferPool& other) {
    for (Kept& kept : kept_) other.keep(std::move(kept.buffer), kept.bytes);
    clear();
}

void BufferPool::clear() {
    kept_.clear();
    bytes_ = 0;
}

}  // namespace kdray
