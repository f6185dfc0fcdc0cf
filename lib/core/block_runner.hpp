// SPDX-License-Identifier: Apache-2.0
// Internal: a way for one component to hand independent blocks of work to
// whatever threads its caller has (the gauge's workers), without knowing
// them. The flatness metrics (fibers in blocks) and the verdict
// (straightedge lines in blocks) take one; a caller without threads runs
// every block itself (inline_block_runner).
#pragma once

#include <cstddef>

namespace flt {

class block_runner {
  public:
    // One block: `participant` (< participants()) names the scratch the
    // block may use; no two blocks run at the same time with the same one.
    using block_fn = void (*)(void *context, std::size_t block, unsigned participant);

    // Runs fn(context, b, p) once for every b in [0, blocks), on any
    // threads in any order, and returns when all have returned. An
    // exception from a block is rethrown here (the first one), after every
    // block has run or been abandoned. Allocates nothing.
    virtual void run(std::size_t blocks, block_fn fn, void *context) = 0;
    // How many blocks may run at once at most: scratch is needed for that many.
    virtual unsigned participants() const = 0;

  protected:
    block_runner() = default;
    ~block_runner() = default;
    block_runner(const block_runner &) = default;
    block_runner &operator=(const block_runner &) = default;
};

// Every block on the calling thread, in order, with participant 0.
class inline_block_runner final : public block_runner {
  public:
    void run(std::size_t blocks, block_fn fn, void *context) override {
        for (std::size_t b = 0; b < blocks; ++b)
            fn(context, b, 0);
    }
    unsigned participants() const override { return 1; }
};

// Runs body(block, participant) through a runner (a lambda as block_fn).
template <class Body> void run_blocks(block_runner &runner, std::size_t blocks, Body &body) {
    runner.run(
        blocks,
        [](void *context, std::size_t block, unsigned participant) {
            (*static_cast<Body *>(context))(block, participant);
        },
        &body);
}

}  // namespace flt
