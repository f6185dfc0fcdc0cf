// SPDX-License-Identifier: Apache-2.0
// Internal: the option registry and the flt_options bag.
//
// Every option key is described once, in the table in options.cpp: its
// name (the binding keyword), bounds, default and integer-ness. A component
// reads a bag through option_value(), which falls back to the default for a
// NULL bag, so `create(..., NULL, ...)` always means "defaults".
#pragma once

#include <cstddef>

#include "flatline/common.h"

namespace flt {

struct option_spec {
    flt_option key;
    const char *name;
    double min_value;
    double max_value;
    double default_value;
    bool is_integer;
};

// The registry entry of key, or nullptr if the key is unknown.
const option_spec *find_option(flt_option key);

// The value of key in options (its default if options is NULL).
double option_value(const flt_options *options, flt_option key);

// True if key was set in options with flt_options_set (false for a NULL
// bag): a value the caller chose, not a default.
bool option_is_set(const flt_options *options, flt_option key);

}  // namespace flt

// Exposed only so option_value() can read it; callers see an opaque type.
struct flt_options {
    static constexpr std::size_t max_keys = 128;
    double value[max_keys];
    bool is_set[max_keys];  // set by flt_options_set, not a default
};
