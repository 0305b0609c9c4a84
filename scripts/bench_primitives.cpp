// bench_primitives.cpp — kdray's data-parallel primitives (cl/runtime/primitives.h) against Boost.Compute's
// on the same ClDevice: exclusive scan (ClPrimitives::exclusive_scan vs
// boost::compute::exclusive_scan) and stream compaction (ClPrimitives::compact vs
// boost::compute::copy_if, and vs Boost's own scan + scatter_if over the same flags array that
// kdray's compact takes). Built only with -DKDRAY_BENCHMARKS=ON; scripts/bench_primitives.sh runs
// it and writes docs/bench-primitives.md.
//
// Fairness: both libraries run on the one context and in-order queue (Boost.Compute wraps kdray's
// cl_context / cl_command_queue) over the very same cl_mem buffers; before timing, a trivial
// program is built so that the runtime's one-time start-up (LLVM in PoCL) is charged to neither;
// every size is warmed up (programs built, PoCL's kernel variants loaded) before it is timed; the
// implementations alternate within each round (A B, then B A) so that load from other processes
// falls on both alike; every call is bracketed by clFinish and the median of the runs is kept.
// Every output is checked against std::exclusive_scan / std::copy_if (outside the timed region,
// after the output buffer was overwritten with a sentinel) and the program aborts on a mismatch.
//
// Output: tab-separated lines "first|steady|varying-new|varying-seen <TAB> op <TAB> impl <TAB> n
// <TAB> milliseconds".
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include <boost/compute/algorithm/copy_if.hpp>
#include <boost/compute/algorithm/exclusive_scan.hpp>
#include <boost/compute/algorithm/scatter_if.hpp>
#include <boost/compute/command_queue.hpp>
#include <boost/compute/container/vector.hpp>
#include <boost/compute/context.hpp>
#include <boost/compute/function.hpp>
#include <boost/compute/iterator/buffer_iterator.hpp>

#include "cl/runtime/device.h"
#include "cl/runtime/primitives.h"

namespace {

namespace bc = boost::compute;
using Clock = std::chrono::steady_clock;

BOOST_COMPUTE_FUNCTION(bool, kd_bench_keep, (cl_uint x), { return (x & 1u) != 0u; });

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

[[noreturn]] void fail(const std::string& what) {
    std::fprintf(stderr, "bench_primitives: MISMATCH: %s\n", what.c_str());
    std::abort();
}

void emit(const char* kind, const char* op, const char* impl, std::size_t n, double ms) {
    std::printf("%s\t%s\t%s\t%zu\t%.4f\n", kind, op, impl, n, ms);
    std::fflush(stdout);
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// The inputs of one size, on the host (for checking) and on the device (shared by both libraries).
struct Inputs {
    std::size_t n = 0;
    std::vector<cl_uint> values, flags;                 // flags[k] = values[k] & 1: about half kept
    std::vector<cl_uint> scan_expected, kept_expected;  // std::exclusive_scan / std::copy_if
    cl::Buffer d_values, d_flags, d_out;                // d_out: n + 1 uints
};

Inputs make_inputs(kdray::ClDevice& device, std::size_t n) {
    Inputs in;
    in.n = n;
    std::mt19937 rng(unsigned(n) * 2654435761u + 1u);
    std::uniform_int_distribution<cl_uint> dist(0, 255);
    in.values.resize(n);
    for (cl_uint& v : in.values) v = dist(rng);
    in.flags.resize(n);
    std::transform(in.values.begin(), in.values.end(), in.flags.begin(),
                   [](cl_uint v) { return v & 1u; });
    in.scan_expected.resize(n);
    std::exclusive_scan(in.values.begin(), in.values.end(), in.scan_expected.begin(), cl_uint(0));
    std::copy_if(in.values.begin(), in.values.end(), std::back_inserter(in.kept_expected),
                 [](cl_uint v) { return (v & 1u) != 0u; });
    const std::size_t bytes = std::max<std::size_t>(n, 1) * sizeof(cl_uint);
    in.d_values = device.allocate(bytes, "bench values");
    in.d_flags = device.allocate(bytes, "bench flags");
    in.d_out = device.allocate(bytes + sizeof(cl_uint), "bench output");
    device.queue().enqueueWriteBuffer(in.d_values, CL_TRUE, 0, n * sizeof(cl_uint),
                                      in.values.data());
    device.queue().enqueueWriteBuffer(in.d_flags, CL_TRUE, 0, n * sizeof(cl_uint), in.flags.data());
    return in;
}

enum class Op { kScan, kCompact };

/// One implementation of one operation: run() enqueues the work and returns the number of output
/// elements (n for a scan, the kept count for a compaction).
struct Impl {
    const char* name;
    Op op;
    std::function<std::size_t(Inputs&)> run;
};

/// Overwrites the output with a sentinel, so that a check never passes on an earlier run's result.
void poison(kdray::ClDevice& device, Inputs& in) {
    device.queue().enqueueFillBuffer(in.d_out, cl_uint(0xDEADBEEFu), 0,
                                     (in.n + 1) * sizeof(cl_uint));
    device.queue().finish();
}

void check(kdray::ClDevice& device, Inputs& in, const Impl& impl, std::size_t count) {
    const std::vector<cl_uint>& expected =
        impl.op == Op::kScan ? in.scan_expected : in.kept_expected;
    const std::string where = std::string(impl.name) + " at n = " + std::to_string(in.n);
    if (count != expected.size())
        fail(where + ": " + std::to_string(count) + " elements, expected " +
             std::to_string(expected.size()));
    std::vector<cl_uint> got(count);
    if (count > 0)
        device.queue().enqueueReadBuffer(in.d_out, CL_TRUE, 0, count * sizeof(cl_uint), got.data());
    const auto bad = std::mismatch(got.begin(), got.end(), expected.begin());
    if (bad.first != got.end()) {
        const std::size_t k = std::size_t(bad.first - got.begin());
        fail(where + ": element " + std::to_string(k) + " is " + std::to_string(*bad.first) +
             ", expected " + std::to_string(*bad.second));
    }
}

/// One timed call: clFinish before and after, then the check (untimed).
double timed_call(kdray::ClDevice& device, Inputs& in, const Impl& impl) {
    poison(device, in);
    const Clock::time_point t0 = Clock::now();
    const std::size_t count = impl.run(in);
    device.queue().finish();
    const double ms = ms_since(t0);
    check(device, in, impl, count);
    return ms;
}

}  // namespace

int main(int argc, char** argv) {
    bool first_only = false;
    int runs = 7;
    std::string selector;
    std::vector<std::size_t> sizes = {1000, 10000, 100000, 1000000, 10000000};
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--first-call-only") {
            first_only = true;
        } else if (a == "--runs" && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--device" && i + 1 < argc) {
            selector = argv[++i];
        } else if (a == "--max-n" && i + 1 < argc) {
            const std::size_t max_n = std::strtoull(argv[++i], nullptr, 10);
            std::erase_if(sizes, [&](std::size_t n) { return n > max_n; });
        } else {
            std::fprintf(stderr,
                         "usage: %s [--first-call-only] [--runs R] [--device SEL] [--max-n N]\n",
                         argv[0]);
            return 2;
        }
    }

    kdray::ClDevice device(selector);
    std::fprintf(stderr, "device: %s (%s), %u compute units\n", device.info().name.c_str(),
                 device.info().version.c_str(), device.info().compute_units);
    bc::context bctx(device.context().get());
    bc::command_queue bqueue(device.queue().get());

    // The runtime's one-time start-up (PoCL loads LLVM on the first build) belongs to neither
    // library: a trivial program absorbs it.
    {
        const Clock::time_point t0 = Clock::now();
        cl::Program warm(device.context(), "kernel void kd_bench_nop(global uint* p) { p[0] = 0; }",
                         true);
        std::fprintf(stderr, "runtime warm-up (trivial program): %.1f ms\n", ms_since(t0));
    }

    // kdray's programs are built when ClPrimitives is constructed; that is part of its first call.
    std::unique_ptr<kdray::ClPrimitives> prims;
    auto kd = [&]() -> kdray::ClPrimitives& {
        if (!prims) prims = std::make_unique<kdray::ClPrimitives>(device);
        return *prims;
    };
    auto it = [](const cl::Buffer& b) {
        return bc::make_buffer_iterator<cl_uint>(bc::buffer(b.get()), 0);
    };

    const std::vector<Impl> impls = {
        {"kdray exclusive_scan", Op::kScan,
         [&](Inputs& in) {
             kd().exclusive_scan(in.d_values, in.d_out, in.n);
             return in.n;
         }},
        {"boost::compute::exclusive_scan", Op::kScan,
         [&](Inputs& in) {
             bc::exclusive_scan(it(in.d_values), it(in.d_values) + in.n, it(in.d_out), bqueue);
             return in.n;
         }},
        {"kdray compact", Op::kCompact,
         [&](Inputs& in) { return kd().compact(in.d_values, in.d_flags, in.d_out, in.n); }},
        {"boost::compute::copy_if", Op::kCompact,
         [&](Inputs& in) {
             const auto end = bc::copy_if(it(in.d_values), it(in.d_values) + in.n, it(in.d_out),
                                          kd_bench_keep, bqueue);
             return std::size_t(end - it(in.d_out));
         }},
        {"boost scan + scatter_if (flags)", Op::kCompact,
         [&](Inputs& in) {
             // kdray's algorithm from Boost's parts, on the same flags array: positions = scan of
             // the flags, count = last position + last flag, scatter the flagged values.
             if (in.n == 0) return std::size_t(0);
             bc::vector<cl_uint> positions(in.n, bctx);
             bc::exclusive_scan(it(in.d_flags), it(in.d_flags) + in.n, positions.begin(), bqueue);
             bc::scatter_if(it(in.d_values), it(in.d_values) + in.n, positions.begin(),
                            it(in.d_flags), it(in.d_out), bqueue);
             const cl_uint last_pos = (positions.end() - 1).read(bqueue);
             const cl_uint last_flag = (it(in.d_flags) + (in.n - 1)).read(bqueue);
             return std::size_t(last_pos + last_flag);
         }},
    };

    // First calls, in a fresh process: the first at n = 1e3 builds each library's programs for
    // that size; Boost.Compute's scan switches from a serial kernel to a parallel one above 64 Ki
    // uints on a CPU device, so a first call at n = 1e6 shows that second build as well.
    std::vector<Inputs> first_inputs;
    for (std::size_t n : {std::size_t(1000), std::size_t(1000000)})
        first_inputs.push_back(make_inputs(device, n));
    for (const Impl& impl : impls)
        for (Inputs& in : first_inputs)
            emit("first", impl.op == Op::kScan ? "scan" : "compact", impl.name, in.n,
                 timed_call(device, in, impl));
    first_inputs.clear();
    if (first_only) return 0;

    for (std::size_t n : sizes) {
        Inputs in = make_inputs(device, n);
        for (Op op : {Op::kScan, Op::kCompact}) {
            std::vector<const Impl*> group;
            for (const Impl& impl : impls)
                if (impl.op == op) group.push_back(&impl);
            for (const Impl* impl : group)
                for (int w = 0; w < 2; ++w) timed_call(device, in, *impl);  // warm-up
            std::vector<std::vector<double>> times(group.size());
            for (int r = 0; r < runs; ++r)
                for (std::size_t j = 0; j < group.size(); ++j) {
                    const std::size_t k = r % 2 ? group.size() - 1 - j : j;
                    times[k].push_back(timed_call(device, in, *group[k]));
                }
            for (std::size_t k = 0; k < group.size(); ++k)
                emit("steady", op == Op::kScan ? "scan" : "compact", group[k]->name, n,
                     median(times[k]));
        }
    }

    // Varying sizes, as in the kd-tree build, where every level's arrays have a new length: one
    // call at each of kVarying sizes never seen before in this process, then the same sizes again.
    // Launches whose local size the runtime picks from the global size (PoCL does) meet a new
    // work-group variant (a compile, or a load from PoCL's cache) at each new size.
    constexpr std::size_t kVarying = 40, kVaryingBase = 100003, kVaryingStep = 1009;
    Inputs base = make_inputs(device, kVaryingBase + kVarying * kVaryingStep);
    std::vector<Inputs> varying;
    for (std::size_t i = 0; i < kVarying; ++i) {
        Inputs in = base;
        in.n = kVaryingBase + i * kVaryingStep;
        in.values.resize(in.n);
        in.scan_expected.resize(in.n);
        in.kept_expected.clear();
        std::copy_if(in.values.begin(), in.values.end(), std::back_inserter(in.kept_expected),
                     [](cl_uint v) { return (v & 1u) != 0u; });
        varying.push_back(std::move(in));
    }
    for (const Impl& impl : impls)
        for (const char* pass : {"varying-new", "varying-seen"}) {
            double total = 0;
            for (Inputs& in : varying) total += timed_call(device, in, impl);
            emit(pass, impl.op == Op::kScan ? "scan" : "compact", impl.name, kVarying, total);
        }
    return 0;
}
