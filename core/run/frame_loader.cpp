#include "core/run/frame_loader.h"

#include <utility>

#include "core/run/frame_pipeline.h"

namespace kdray {
namespace {

std::future<LoadedScene> load_async(const std::string& path) {
    return std::async(std::launch::async, [path] {
        auto start = FrameClock::now();
        Scene scene = load_obj(path);
        return LoadedScene{std::move(scene), ms_since(start)};
    });
}

}  // namespace

FrameLoader::FrameLoader(std::vector<std::string> paths, Overlap overlap)
    : paths_(std::move(paths)), overlap_(overlap) {
    start_next();
}

void FrameLoader::start_next() {
    if (next_ < paths_.size() && !loading_.valid() && !kept_) loading_ = load_async(paths_[next_]);
}

LoadedScene FrameLoader::take() {
    std::optional<LoadedScene> kept = std::move(kept_);
    kept_.reset();
    std::future<LoadedScene> pending;
    if (!kept) pending = loading_.valid() ? std::move(loading_) : load_async(paths_.at(next_));
    ++next_;
    if (overlap_ == Overlap::Compute) start_next();
    if (kept) return std::move(*kept);
    return pending.get();
}

const LoadedScene& FrameLoader::peek() {
    if (!kept_) {
        std::future<LoadedScene> pending =
            loading_.valid() ? std::move(loading_) : load_async(paths_.at(next_));
        kept_ = pending.get();
    }
    return *kept_;
}

void FrameLoader::computed() {
    start_next();
}

}  // namespace kdray
