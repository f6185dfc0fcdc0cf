// SPDX-License-Identifier: Apache-2.0
// Internal: files named by the UTF-8 paths the C API takes.
//
// Every path in the C API is UTF-8 on every platform. On Linux those bytes
// are the file name as they are. On Windows the narrow C and C++ calls
// (fopen, std::ifstream(const char *), cv::imread, opendir) read a char path
// in the ANSI code page, so "Jürgen.json" would name "JÃ¼rgen.json": there
// the helpers below convert to UTF-16 and use the wide calls. Every file the
// library opens goes through them:
//
//     std::FILE *f = flt::open_file(path, "rb");          // like std::fopen
//     std::ifstream in(flt::utf8_path(path), std::ios::binary);
//     flt::read_file(path, bytes, max_bytes);             // whole file (imdecode)
//     flt::replace_file(tmp, path);                       // rename over a file
//     for (auto &e : std::filesystem::directory_iterator(flt::utf8_path(dir)))
//         names.push_back(flt::utf8_string(e.path().filename()));
#pragma once

#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace flt {

// The std::filesystem::path a UTF-8 string names (UTF-16 inside on
// Windows). Throws flt::error (FLT_ERR_INVALID_ARGUMENT) on Windows when the
// bytes are not valid UTF-8, which no file name can be there.
std::filesystem::path utf8_path(const std::string &utf8);
std::filesystem::path utf8_path(const char *utf8);

// A path as UTF-8 (for messages and for paths handed back to the caller).
std::string utf8_string(const std::filesystem::path &path);

// std::fopen of a UTF-8 path (_wfopen on Windows). nullptr with errno set
// on failure (EILSEQ when the path is not valid UTF-8 on Windows).
std::FILE *open_file(const char *utf8, const char *mode);
inline std::FILE *open_file(const std::string &utf8, const char *mode) {
    return open_file(utf8.c_str(), mode);
}

// Reads a whole file into `bytes`. The error is empty on success;
// std::errc::file_too_large when the file has more than max_bytes bytes
// (nothing beyond max_bytes + 1 is read).
std::error_code read_file(const std::string &utf8, std::string &bytes, std::size_t max_bytes);

// Renames `from` onto `to`, replacing `to` when it exists, in one step where
// the file system allows it: rename(2) on POSIX, MoveFileExW with
// MOVEFILE_REPLACE_EXISTING on Windows (whose rename refuses an existing
// target). The error is empty on success.
std::error_code replace_file(const std::string &from, const std::string &to);

// Removes a file; errors are ignored (used to clean up after a failure).
void remove_file(const std::string &utf8) noexcept;

}  // namespace flt
