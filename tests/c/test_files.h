// SPDX-License-Identifier: Apache-2.0
/*
 * Files and folders for the C tests, on Linux and Windows alike.
 *
 * Paths are UTF-8, as in libflatline's API. On Windows these helpers use the
 * wide (UTF-16) calls, so a test can create "Jürgen.json" under its real
 * name and check that the library found (or wrote) exactly that file: the
 * narrow calls would read the bytes in the ANSI code page instead.
 *
 *   tf_temp_dir(buf, size, "tag")  a new empty folder in the system's
 *                                  temporary folder (0 on success)
 *   tf_fopen(path, mode)           fopen
 *   tf_mkdir(path)                 mkdir (0 on success)
 *   tf_remove(path)                remove a file or an empty folder
 *   tf_exists(path)                1 when a file or folder of that name exists
 *   tf_remove_tree(path)           remove a folder and everything in it
 */
#ifndef FLT_TEST_FILES_H
#define FLT_TEST_FILES_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#  ifndef WIN32_LEAN_AND_MEAN
#    define WIN32_LEAN_AND_MEAN
#  endif
#  include <windows.h>
#  include <wchar.h>

/* UTF-8 -> UTF-16 into a caller's buffer; 0 on success. */
static inline int tf_widen(const char *utf8, wchar_t *out, int cap) {
    int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8, -1, out, cap);
    return n > 0 ? 0 : -1;
}

static inline FILE *tf_fopen(const char *path, const char *mode) {
    wchar_t wpath[1024], wmode[16];
    if (tf_widen(path, wpath, 1024) || tf_widen(mode, wmode, 16))
        return NULL;
    return _wfopen(wpath, wmode);
}

static inline int tf_mkdir(const char *path) {
    wchar_t w[1024];
    if (tf_widen(path, w, 1024))
        return -1;
    return CreateDirectoryW(w, NULL) ? 0 : -1;
}

static inline int tf_remove(const char *path) {
    wchar_t w[1024];
    if (tf_widen(path, w, 1024))
        return -1;
    if (DeleteFileW(w))
        return 0;
    return RemoveDirectoryW(w) ? 0 : -1;
}

static inline int tf_exists(const char *path) {
    wchar_t w[1024];
    if (tf_widen(path, w, 1024))
        return 0;
    return GetFileAttributesW(w) != INVALID_FILE_ATTRIBUTES;
}

static inline int tf_remove_tree_w(const wchar_t *dir) {
    wchar_t pattern[1100];
    if (_snwprintf(pattern, 1100, L"%ls\\*", dir) < 0)
        return -1;
    WIN32_FIND_DATAW e;
    HANDLE h = FindFirstFileW(pattern, &e);
    if (h != INVALID_HANDLE_VALUE) {
        do {
            if (wcscmp(e.cFileName, L".") == 0 || wcscmp(e.cFileName, L"..") == 0)
                continue;
            wchar_t child[1100];
            _snwprintf(child, 1100, L"%ls\\%ls", dir, e.cFileName);
            if (e.dwFileAttributes & FILE_ATTRIBUTE_DIRECTORY)
                tf_remove_tree_w(child);
            else
                DeleteFileW(child);
        } while (FindNextFileW(h, &e));
        FindClose(h);
    }
    return RemoveDirectoryW(dir) ? 0 : -1;
}

static inline int tf_remove_tree(const char *path) {
    wchar_t w[1024];
    if (tf_widen(path, w, 1024))
        return -1;
    return tf_remove_tree_w(w);
}

static inline int tf_temp_dir(char *out, size_t cap, const char *tag) {
    wchar_t base[MAX_PATH + 1];
    DWORD n = GetTempPathW(MAX_PATH + 1, base);
    if (n == 0 || n > MAX_PATH)
        return -1;
    char base8[4 * MAX_PATH];
    if (WideCharToMultiByte(CP_UTF8, 0, base, -1, base8, (int)sizeof base8, NULL, NULL) <= 0)
        return -1;
    static unsigned counter;
    for (int attempt = 0; attempt < 100; ++attempt) {
        snprintf(out, cap, "%sflt_%s_%lu_%u", base8, tag, (unsigned long)GetCurrentProcessId(),
                 counter++);
        if (tf_mkdir(out) == 0)
            return 0;
    }
    return -1;
}
#else
#  include <dirent.h>
#  include <sys/stat.h>
#  include <unistd.h>

static inline FILE *tf_fopen(const char *path, const char *mode) {
    return fopen(path, mode);
}

static inline int tf_mkdir(const char *path) {
    return mkdir(path, 0700);
}

static inline int tf_remove(const char *path) {
    return remove(path);
}

static inline int tf_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static inline int tf_remove_tree(const char *path) {
    DIR *d = opendir(path);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            char child[4096];
            const int n = snprintf(child, sizeof child, "%s/%s", path, e->d_name);
            if (n < 0 || n >= (int)sizeof child)
                continue;
            struct stat st;
            if (lstat(child, &st) == 0 && S_ISDIR(st.st_mode))
                tf_remove_tree(child);
            else
                remove(child);
        }
        closedir(d);
    }
    return rmdir(path);
}

static inline int tf_temp_dir(char *out, size_t cap, const char *tag) {
    const char *base = getenv("TMPDIR");
    if (!base || !*base)
        base = "/tmp";
    if ((size_t)snprintf(out, cap, "%s/flt_%s_XXXXXX", base, tag) >= cap)
        return -1;
    return mkdtemp(out) ? 0 : -1;
}
#endif

#endif
