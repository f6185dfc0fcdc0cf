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
#else
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);

void *malloc(size_t n) {
    if (atomic_load(&g_counting))
        atomic_fetch_add(&g_allocations, 1);
    return __libc_malloc(n);
}
void *calloc(size_t n, size_t size) {
    if (atomic_load(&g_counting))
        atomic_fetch_add(&g_allocations, 1);
    return __libc_calloc(n, size);
}
void *realloc(void *p, size_t n) {
    if (atomic_load(&g_counting))
        atomic_fetch_add(&g_allocations, 1);
    return __libc_realloc(p, n);
}
void free(void *p) {
    __libc_free(p);
}

int alloc_count_install(void) {
    return 1;
}
#endif
