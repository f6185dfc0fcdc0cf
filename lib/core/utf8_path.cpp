// SPDX-License-Identifier: Apache-2.0
#include "core/utf8_path.hpp"

#include <cerrno>
#include <cstring>

#include "core/error.hpp"

#ifdef _WIN32
#  ifndef WIN32_LEAN_AND_MEAN
#    define WIN32_LEAN_AND_MEAN
#  endif
#  ifndef NOMINMAX
#    define NOMINMAX
#  endif
#  include <windows.h>
#endif

namespace flt {

#ifdef _WIN32
namespace {
// UTF-8 -> UTF-16; false when the bytes are not valid UTF-8.
bool widen(const char *utf8, std::wstring &out) {
    out.clear();
    const std::size_t length = std::strlen(utf8);
    if (length == 0)
        return true;
    if (length > 0x7fffffff)
        return false;
    const int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8, int(length), nullptr, 0);
    if (n <= 0)
        return false;
    out.resize(std::size_t(n));
    return MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8, int(length), &out[0], n) == n;
}

std::string narrow(const std::wstring &utf16) {
    if (utf16.empty())
        return std::string();
    const int n = WideCharToMultiByte(CP_UTF8, 0, utf16.data(), int(utf16.size()), nullptr, 0,
                                      nullptr, nullptr);
    if (n <= 0)
        return std::string();
    std::string out(std::size_t(n), '\0');
    WideCharToMultiByte(CP_UTF8, 0, utf16.data(), int(utf16.size()), &out[0], n, nullptr, nullptr);
    return out;
}
}  // namespace
#endif

std::filesystem::path utf8_path(const char *utf8) {
#ifdef _WIN32
    std::wstring wide;
    if (!widen(utf8, wide))
        throw error(FLT_ERR_INVALID_ARGUMENT, "the path is not valid UTF-8");
    return std::filesystem::path(wide);
#else
    return std::filesystem::path(utf8);
#endif
}

std::filesystem::path utf8_path(const std::string &utf8) {
    return utf8_path(utf8.c_str());
}

std::string utf8_string(const std::filesystem::path &path) {
#ifdef _WIN32
    return narrow(path.native());
#else
    return path.native();
#endif
}

std::FILE *open_file(const char *utf8, const char *mode) {
#ifdef _WIN32
    std::wstring wide_path, wide_mode;
    if (!widen(utf8, wide_path) || !widen(mode, wide_mode)) {
        errno = EILSEQ;
        return nullptr;
    }
    return _wfopen(wide_path.c_str(), wide_mode.c_str());
#else
    return std::fopen(utf8, mode);
#endif
}

std::error_code read_file(const std::string &utf8, std::string &bytes, std::size_t max_bytes) {
    bytes.clear();
    std::FILE *f = open_file(utf8, "rb");
    if (!f)
        return std::error_code(errno, std::generic_category());
    char chunk[65536];
    std::size_t got;
    while ((got = std::fread(chunk, 1, sizeof chunk, f)) > 0) {
        bytes.append(chunk, got);
        if (bytes.size() > max_bytes) {
            std::fclose(f);
            bytes.clear();
            return std::make_error_code(std::errc::file_too_large);
        }
    }
    const bool failed = std::ferror(f) != 0;
    std::fclose(f);
    if (failed) {
        bytes.clear();
        return std::make_error_code(std::errc::io_error);
    }
    return std::error_code();
}

std::error_code replace_file(const std::string &from, const std::string &to) {
#ifdef _WIN32
    std::wstring wide_from, wide_to;
    if (!widen(from.c_str(), wide_from) || !widen(to.c_str(), wide_to))
        return std::make_error_code(std::errc::illegal_byte_sequence);
    if (MoveFileExW(wide_from.c_str(), wide_to.c_str(),
                    MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH))
        return std::error_code();
    return std::error_code(int(GetLastError()), std::system_category());
#else
    if (std::rename(from.c_str(), to.c_str()) == 0)
        return std::error_code();
    return std::error_code(errno, std::generic_category());
#endif
}

void remove_file(const std::string &utf8) noexcept {
#ifdef _WIN32
    std::wstring wide;
    if (widen(utf8.c_str(), wide))
        _wremove(wide.c_str());
#else
    std::remove(utf8.c_str());
#endif
}

}  // namespace flt
