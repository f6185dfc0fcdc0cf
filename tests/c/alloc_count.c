// SPDX-License-Identifier: Apache-2.0
/* The counting allocator; alloc_count.h says how it works per platform. */
#include "alloc_count.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "flatline/flatline.h"

atomic_int g_counting;
atomic_size_t g_allocations;

#ifdef _WIN32
#  include <malloc.h>
#  include <windows.h>

static void *(*real_malloc)(size_t);
static void *(*real_calloc)(size_t, size_t);
static void *(*real_realloc)(void *, size_t);
static void *(*real_aligned_malloc)(size_t, size_t);
static void *(*real_aligned_realloc)(void *, size_t, size_t);
static void *(*real_recalloc)(void *, size_t, size_t);

static void count(void) {
    if (atomic_load(&g_counting))
        atomic_fetch_add(&g_allocations, 1);
}
static void *counting_malloc(size_t n) {
    count();
    return real_malloc(n);
}
static void *counting_calloc(size_t n, size_t size) {
    count();
    return real_calloc(n, size);
}
static void *counting_realloc(void *p, size_t n) {
    count();
    return real_realloc(p, n);
}
static void *counting_aligned_malloc(size_t n, size_t alignment) {
    count();
    return real_aligned_malloc(n, alignment);
}
static void *counting_aligned_realloc(void *p, size_t n, size_t alignment) {
    count();
    return real_aligned_realloc(p, n, alignment);
}
static void *counting_recalloc(void *p, size_t n, size_t size) {
    count();
    return real_recalloc(p, n, size);
}

struct hook {
    const char *name;
    void **real;
    void *counting;
};

int alloc_count_install(void) {
    static int hooked = -1;
    if (hooked >= 0)
        return hooked;
    hooked = 0;
    const struct hook hooks[] = {
        {"malloc", (void **)&real_malloc, (void *)counting_malloc},
        {"calloc", (void **)&real_calloc, (void *)counting_calloc},
        {"realloc", (void **)&real_realloc, (void *)counting_realloc},
        {"_aligned_malloc", (void **)&real_aligned_malloc, (void *)counting_aligned_malloc},
        {"_aligned_realloc", (void **)&real_aligned_realloc, (void *)counting_aligned_realloc},
        {"_recalloc", (void **)&real_recalloc, (void *)counting_recalloc},
    };
    HMODULE module = NULL;
    if (!GetModuleHandleExA(GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS |
                                GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT,
                            (LPCSTR)(uintptr_t)&flt_version, &module))
        return 0;
    unsigned char *base = (unsigned char *)module;
    const IMAGE_DOS_HEADER *dos = (const IMAGE_DOS_HEADER *)base;
    const IMAGE_NT_HEADERS64 *nt = (const IMAGE_NT_HEADERS64 *)(base + dos->e_lfanew);
    const IMAGE_DATA_DIRECTORY dir = nt->OptionalHeader.DataDirectory[IMAGE_DIRECTORY_ENTRY_IMPORT];
    if (dir.VirtualAddress == 0)
        return 0;
    for (const IMAGE_IMPORT_DESCRIPTOR *d =
             (const IMAGE_IMPORT_DESCRIPTOR *)(base + dir.VirtualAddress);
         d->Name != 0; ++d) {
        /* The names (original thunks) beside the addresses the loader wrote. */
        const IMAGE_THUNK_DATA64 *names =
            (const IMAGE_THUNK_DATA64 *)(base + (d->OriginalFirstThunk ? d->OriginalFirstThunk
                                                                       : d->FirstThunk));
        IMAGE_THUNK_DATA64 *iat = (IMAGE_THUNK_DATA64 *)(base + d->FirstThunk);
        for (; names->u1.AddressOfData != 0; ++names, ++iat) {
            if (IMAGE_SNAP_BY_ORDINAL64(names->u1.Ordinal))
                continue;
            const IMAGE_IMPORT_BY_NAME *by_name =
                (const IMAGE_IMPORT_BY_NAME *)(base + names->u1.AddressOfData);
            for (size_t h = 0; h < sizeof hooks / sizeof hooks[0]; ++h) {
                if (strcmp((const char *)by_name->Name, hooks[h].name) != 0)
                    continue;
                DWORD old;
                if (!VirtualProtect(&iat->u1.Function, sizeof iat->u1.Function, PAGE_READWRITE,
                                    &old))
                    continue;
                *hooks[h].real = (void *)(uintptr_t)iat->u1.Function;
                iat->u1.Function = (ULONGLONG)(uintptr_t)hooks[h].counting;
                VirtualProtect(&iat->u1.Function, sizeof iat->u1.Function, old, &old);
                if (strcmp(hooks[h].name, "malloc") == 0)
                    ++hooked;
            }
        }
    }
    return hooked;
}
size_t alloc_live_bytes(void) {
    return 0;
}
size_t alloc_peak_bytes(void) {
    return 0;
}
void alloc_reset_peak(void) {}
#else
#  include <errno.h>
#  include <malloc.h>

extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);
extern void __libc_free(void *);

/* Bytes held, as malloc_usable_size reports them (what the allocator set
 * aside for each block, a few bytes above what was asked), and their peak. */
static atomic_size_t live_bytes;
static atomic_size_t peak_bytes;

static void *held(void *p) {
    if (p != NULL) {
        size_t now = atomic_fetch_add(&live_bytes, malloc_usable_size(p)) + malloc_usable_size(p);
        size_t peak = atomic_load(&peak_bytes);
        while (now > peak && !atomic_compare_exchange_weak(&peak_bytes, &peak, now)) {
        }
    }
    return p;
}
static void released(void *p) {
    if (p != NULL)
        atomic_fetch_sub(&live_bytes, malloc_usable_size(p));
}
static void count(void) {
    if (atomic_load(&g_counting))
        atomic_fetch_add(&g_allocations, 1);
}

void *malloc(size_t n) {
    count();
    return held(__libc_malloc(n));
}
void *calloc(size_t n, size_t size) {
    count();
    return held(__libc_calloc(n, size));
}
void *realloc(void *p, size_t n) {
    count();
    released(p);
    void *moved = __libc_realloc(p, n);
    if (moved == NULL && n != 0) {  // p is still held
        held(p);
        return NULL;
    }
    return held(moved);
}
/* The aligned forms (operator new of over-aligned types, Eigen, OpenCV)
 * come back to free(): they must be counted on the way in too. */
void *memalign(size_t alignment, size_t n) {
    count();
    return held(__libc_memalign(alignment, n));
}
void *aligned_alloc(size_t alignment, size_t n) {
    count();
    return held(__libc_memalign(alignment, n));
}
int posix_memalign(void **out, size_t alignment, size_t n) {
    if (alignment < sizeof(void *) || (alignment & (alignment - 1)) != 0)
        return EINVAL;
    count();
    void *p = held(__libc_memalign(alignment, n));
    if (p == NULL && n != 0)
        return ENOMEM;
    *out = p;
    return 0;
}
void free(void *p) {
    released(p);
    __libc_free(p);
}

int alloc_count_install(void) {
    return 1;
}
size_t alloc_live_bytes(void) {
    return atomic_load(&live_bytes);
}
size_t alloc_peak_bytes(void) {
    return atomic_load(&peak_bytes);
}
void alloc_reset_peak(void) {
    atomic_store(&peak_bytes, atomic_load(&live_bytes));
}
#endif
