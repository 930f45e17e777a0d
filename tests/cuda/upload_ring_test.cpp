// The upload ring (src/cuda/upload_ring.h) on a device: while the stream is held up (a host
// function that sleeps, as a step in flight), the ring hands out bytes for many uploads
// without waiting; going round onto bytes a pending copy still reads, it waits for that copy
// and no other; every copy delivers what was written. Skips with the reason without a device.
#include "cuda_test_support.h"

#include "cuda/upload_ring.h"

#include <cuda_runtime_api.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <thread>
#include <vector>

namespace hmsm::cuda_test {
namespace {

using detail::cuda::UploadRing;

/// Holds `stream` up for `ms` milliseconds: the copies enqueued after it wait.
void hold_up(cudaStream_t stream, int ms) {
    static int held;
    held = ms;
    ASSERT_EQ(cudaLaunchHostFunc(
                  stream, [](void*) { std::this_thread::sleep_for(std::chrono::milliseconds(held)); }, nullptr),
              cudaSuccess);
}

struct Copies {
    cudaStream_t stream = nullptr;
    std::byte* device = nullptr;
    ~Copies() {
        if (stream) (void)cudaStreamSynchronize(stream);
        if (device) (void)cudaFree(device);
        if (stream) (void)cudaStreamDestroy(stream);
    }
};

/// Acquires `bytes`, fills them with `value` and copies them to device + `at` on the stream.
void upload(UploadRing& ring, Copies& c, uint64_t at, uint64_t bytes, uint8_t value) {
    auto staging = ring.acquire(bytes);
    ASSERT_TRUE(staging.ok()) << staging.status().message();
    std::memset(*staging, value, bytes);
    ASSERT_EQ(cudaMemcpyAsync(c.device + at, *staging, bytes, cudaMemcpyHostToDevice, c.stream), cudaSuccess);
    ASSERT_TRUE(ring.mark(c.stream).ok());
}

/// Every block k of `bytes` at device + k * bytes holds the value k + 1.
void expect_blocks(Copies& c, uint32_t blocks, uint64_t bytes) {
    ASSERT_EQ(cudaStreamSynchronize(c.stream), cudaSuccess);
    std::vector<uint8_t> back(blocks * bytes);
    ASSERT_EQ(cudaMemcpy(back.data(), c.device, back.size(), cudaMemcpyDeviceToHost), cudaSuccess);
    for (uint32_t k = 0; k < blocks; ++k)
        for (uint64_t b = 0; b < bytes; b += 997) ASSERT_EQ(back[k * bytes + b], uint8_t(k + 1)) << "block " << k;
}

TEST(CudaUploadRing, ManyUploadsBehindAHeldStreamWaitForNothing) {
    HMSM_SKIP_WITHOUT_CUDA();
    Copies c;
    ASSERT_EQ(cudaStreamCreate(&c.stream), cudaSuccess);
    constexpr uint32_t kBlocks = 200;  // a frame's writes, far more than a ring of slots held
    constexpr uint64_t kBytes = 5000;  // not a multiple of the ring's alignment
    ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&c.device), kBlocks * kBytes), cudaSuccess);
    UploadRing ring;
    hold_up(c.stream, 100);
    for (uint32_t k = 0; k < kBlocks; ++k) upload(ring, c, k * kBytes, kBytes, uint8_t(k + 1));
    EXPECT_EQ(ring.waits(), 0u);
    expect_blocks(c, kBlocks, kBytes);
}

TEST(CudaUploadRing, GoingRoundWaitsForTheCopyItsBytesHeldOnly) {
    HMSM_SKIP_WITHOUT_CUDA();
    Copies c;
    ASSERT_EQ(cudaStreamCreate(&c.stream), cudaSuccess);
    UploadRing ring;
    ASSERT_TRUE(ring.acquire(1).ok());  // sizes the ring; never marked, so its bytes are free again
    const uint64_t quarter = ring.capacity() / 4;
    ASSERT_GT(quarter, 0u);
    ASSERT_EQ(cudaMalloc(reinterpret_cast<void**>(&c.device), 6 * quarter), cudaSuccess);
    hold_up(c.stream, 100);
    for (uint32_t k = 0; k < 4; ++k) upload(ring, c, k * quarter, quarter, uint8_t(k + 1));
    EXPECT_EQ(ring.waits(), 0u);  // the ring is full, nothing reused yet
    // The fifth takes the first quarter again: it waits for the first copy (behind the held
    // stream), and only for it.
    upload(ring, c, 4 * quarter, quarter, 5);
    EXPECT_EQ(ring.waits(), 1u);
    upload(ring, c, 5 * quarter, quarter / 2, 6);
    expect_blocks(c, 5, quarter);
    std::vector<uint8_t> last(quarter / 2);
    ASSERT_EQ(cudaMemcpy(last.data(), c.device + 5 * quarter, last.size(), cudaMemcpyDeviceToHost), cudaSuccess);
    EXPECT_EQ(last.front(), 6);
    EXPECT_EQ(last.back(), 6);
}

TEST(CudaUploadRing, AnAcquireNeverMarkedGivesItsBytesBack) {
    HMSM_SKIP_WITHOUT_CUDA();
    UploadRing ring;
    auto first = ring.acquire(1000);
    ASSERT_TRUE(first.ok());
    auto again = ring.acquire(1000);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(*first, *again);
    // A request over half the ring grows it.
    const uint64_t before = ring.capacity();
    ASSERT_TRUE(ring.acquire(before).ok());
    EXPECT_GE(ring.capacity(), 2 * before);
}

}  // namespace
}  // namespace hmsm::cuda_test
