// SPDX-License-Identifier: Apache-2.0
/*
 * The counting allocator of the "no allocation in hot paths" tests: every
 * malloc, calloc and realloc made while g_counting is set is counted in
 * g_allocations, including those of libflatline and the C++ runtime inside
 * it (operator new calls malloc).
 *
 * Linux: the test executable defines malloc, calloc, realloc and free; ELF
 * symbol interposition makes the shared library call them too.
 * Windows: a DLL binds its C runtime imports itself, so interposition does
 * not exist there; alloc_count_install() rewrites the loaded libflatline
 * DLL's import address table entries of the C runtime's allocation
 * functions (malloc, calloc, realloc, _aligned_malloc, _aligned_realloc,
 * _recalloc) to counting wrappers. It returns how many entries it hooked
 * (at least malloc's, or the counts would be blind: the tests assert it)
 * and is a no-op returning 1 on Linux.
 *
 * The tests keep a control: the counter must see the allocations a create
 * call makes, so a hook that does not work fails the test. The counter and
 * the switch are atomics: the gauge allocates (or must not) on threads of
 * its own.
 */
#ifndef FLT_ALLOC_COUNT_H
#define FLT_ALLOC_COUNT_H

#include <stdatomic.h>
#include <stddef.h>

extern atomic_int g_counting;
extern atomic_size_t g_allocations;

int alloc_count_install(void);

/* Linux only (0 on Windows, where the hooks see one DLL's calls): the bytes
 * the process holds in the heap now, their peak since alloc_reset_peak(),
 * counted from malloc_usable_size for every block, with or without
 * g_counting. The memory tests compare a create call's peak with the
 * formula its header documents. */
size_t alloc_live_bytes(void);
size_t alloc_peak_bytes(void);
void alloc_reset_peak(void);

#endif
