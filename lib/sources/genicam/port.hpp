// SPDX-License-Identifier: Apache-2.0
// Internal: the seam between the GenICam node map and a camera's registers.
// A transport (USB3 Vision GenCP, GigE Vision GVCP, a memory image in the
// offline view) implements it; the node map reads and writes through it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace flt::genicam {

// Raw register access on one GenICam port (the XML's <Port> node).
//
// Bytes move unchanged, in the device's memory order: the node map applies
// each register's <Endianess> (USB3 Vision registers are little endian,
// GigE Vision registers big endian). An implementation splits requests to
// its transport's limits itself (GenCP packet sizes, GVCP 536-byte reads).
//
// Errors: throw flt::error (lib/core/error.hpp) with the status the caller
// should see (FLT_ERR_DEVICE for a refused or failed transaction,
// FLT_ERR_TIMEOUT, FLT_ERR_NOT_FOUND for memory the offline view was not
// given) and a message naming the address; the node map adds the feature
// and the node chain to it. Anything else thrown is a bug.
//
// Threads: the node map calls a port from the thread that uses the node map.
class register_port {
  public:
    virtual ~register_port() = default;
    virtual void read(std::uint64_t address, std::uint8_t *out, std::size_t bytes) = 0;
    virtual void write(std::uint64_t address, const std::uint8_t *in, std::size_t bytes) = 0;
};

}  // namespace flt::genicam
