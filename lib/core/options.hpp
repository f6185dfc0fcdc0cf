// SPDX-License-Identifier: Apache-2.0
// Internal: the option registry and the flt_options bag.
//
// Every option key is described once, in the table in options.cpp: its
// name (the binding keyword), bounds, default and integer-ness. A component
// reads a bag through option_value(), which falls back to the default for a
// NULL bag, so `create(..., NULL, ...)` always means "defaults".
#pragma once

#include <cstddef>
#include <initializer_list>

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

// Option keys are numbered by component, a hundred each (common.h):
// 100s the reconstructor, 200s calibration, 300s the simulator, 400s the
// extractor, 500s flatness, 600s frame sources, 700s the gauge, 800s
// quality verdicts, 900s the advisor. The component of a key, e.g.
// "the simulator" ("another component" outside those ranges).
const char *option_component(int key);

// Every component's create calls this with its range (100 for the
// reconstructor, ...) before reading a bag: a key the caller set that
// belongs to another component would be silently ignored, which hides a
// mistake (a typo'd bag, options meant for another stage). Fails with
// FLT_ERR_INVALID_ARGUMENT naming the key and the components; a NULL bag
// passes. A component built on others lists every range it reads, its
// own first (the message names it).
flt_status check_option_component(const char *fn, const flt_options *options,
                                  std::initializer_list<int> ranges);

// A bag of defaults, as flt_options_create makes it (nothing set).
flt_options default_options();

// The keys of one component (its range: 100 for the reconstructor, ...)
// as the caller set them in from, every other key at its default and not
// set: what a component built on others hands each part (a NULL bag gives
// the defaults).
flt_options component_options(const flt_options *from, int range);

// The named values of an option whose value is a choice (robust,
// flat_reference, source_encoder_mode): the C enumerators in the
// component's header, and the lower-case names the bindings accept.
struct option_choice {
    flt_option key;
    const char *name;
    int value;
};

}  // namespace flt

// Exposed only so option_value() can read it; callers see an opaque type.
struct flt_options {
    static constexpr std::size_t max_keys = 192;
    double value[max_keys];
    bool is_set[max_keys];  // set by flt_options_set, not a default
};
