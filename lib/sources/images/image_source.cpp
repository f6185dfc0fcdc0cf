// SPDX-License-Identifier: Apache-2.0
// Recorded image sequences as a frame source. OpenCV decodes one file per
// next() into the same cv::Mat (its decoder allocates: an offline path).
// Files are named by UTF-8 paths (core/utf8_path).
// Block id = index of the file; the position comes from the CSV file or
// follows the fixed step.
#include "sources/images/image_source.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <system_error>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "core/utf8_path.hpp"

namespace flt::sources {

namespace {

std::uint64_t host_ns() {
    return std::uint64_t(std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::steady_clock::now().time_since_epoch())
                             .count());
}

std::string base_name(const std::string &path) {
    const std::size_t slash = path.find_last_of("/\\");
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool has_image_suffix(const std::string &name) {
    std::string lower = name;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    const char *const suffixes[] = {".png", ".tif", ".tiff"};
    return std::any_of(std::begin(suffixes), std::end(suffixes), [&lower](const char *s) {
        const std::size_t n = std::strlen(s);
        return lower.size() > n && lower.compare(lower.size() - n, n, s) == 0;
    });
}

class image_source final : public source_impl {
  public:
    image_source(std::vector<std::string> paths, int bits)
        : paths_(std::move(paths)), option_bits_(bits) {}

    void read_csv(const std::string &csv);
    void open_first();

    flt_source_kind kind() const override { return FLT_SOURCE_IMAGES; }

    void start() override {
        // A started sequence starts again from its first image.
        if (next_index_ > 0) {
            next_index_ = 0;
            load(0);
        }
    }
    void stop() override {}

    bool next(unsigned /*timeout_ms*/, raw_frame &out) override {
        if (next_index_ >= paths_.size())
            return false;  // end of the sequence
        const std::size_t index = std::size_t(next_index_++);
        if (index > 0)
            load(index);
        const bool wide = image_.depth() == CV_16U;
        if (std::uint32_t(image_.cols) != width_ || std::uint32_t(image_.rows) != height_ ||
            wide != (bits_ > 8))
            raise(FLT_ERR_FORMAT,
                  "image %zu '%.200s' is %d x %d, %d bits; the sequence "
                  "started with %u x %u, %d bits",
                  index, paths_[index].c_str(), image_.cols, image_.rows, wide ? 16 : 8, width_,
                  height_, bits_ > 8 ? 16 : 8);
        out.pixels = image_.data;
        out.width = width_;
        out.height = height_;
        out.stride = image_.step[0];
        out.bytes = image_.step[0] * std::size_t(image_.rows);
        out.format = flt_pixel_format(bits_);
        out.block_id = index;
        out.timestamp_ns = host_ns();
        // Without a CSV the position follows the fixed step (NaN here).
        out.own_encoder_mm =
            csv_encoder_.empty() ? std::numeric_limits<double>::quiet_NaN() : csv_encoder_[index];
        return true;
    }

    std::uint64_t count(flt_source_counter which) const override {
        // Images lose nothing: only delivered frames count.
        return which == FLT_COUNT_FRAMES ? next_index_ : 0;
    }

  private:
    // Reads image `index` into image_ and checks it.
    void load(std::size_t index) {
        const std::string &path = paths_[index];
        // Read here and decoded from memory: cv::imread takes a narrow
        // path, which Windows reads in the ANSI code page, not UTF-8
        // (core/utf8_path). 1 GiB is far beyond any camera frame and below
        // INT_MAX, the longest row a cv::Mat can have.
        constexpr std::size_t k_max_image_bytes = std::size_t(1) << 30;
        if (const std::error_code err = read_file(path, file_bytes_, k_max_image_bytes))
            raise(FLT_ERR_IO, "image %zu '%.200s' cannot be read (missing or not readable: %s)",
                  index, path.c_str(), err.message().c_str());
        image_ = file_bytes_.empty()
                     ? cv::Mat()
                     : cv::imdecode(cv::Mat(1, int(file_bytes_.size()), CV_8U, file_bytes_.data()),
                                    cv::IMREAD_UNCHANGED);
        if (image_.empty())
            raise(FLT_ERR_IO,
                  "image %zu '%.200s' cannot be read (missing, or not an "
                  "image OpenCV can decode)",
                  index, path.c_str());
        if (image_.channels() != 1)
            raise(FLT_ERR_FORMAT,
                  "image %zu '%.200s' has %d channels; a laser frame is "
                  "monochrome (1 channel)",
                  index, path.c_str(), image_.channels());
        if (image_.depth() != CV_8U && image_.depth() != CV_16U)
            raise(FLT_ERR_FORMAT, "image %zu '%.200s' is neither 8 nor 16 bits per pixel", index,
                  path.c_str());
    }

    std::vector<std::string> paths_;
    std::vector<double> csv_encoder_;
    int option_bits_ = 0;  // source_image_bits
    int bits_ = 8;         // of the frames delivered: 8, 10, 12 or 16
    std::uint32_t width_ = 0, height_ = 0;
    cv::Mat image_;
    std::string file_bytes_;  // the current image file, decoded into image_
    std::uint64_t next_index_ = 0;
};

void image_source::read_csv(const std::string &csv) {
    std::ifstream in(utf8_path(csv));
    if (!in)
        raise(FLT_ERR_IO, "encoder CSV '%.200s' cannot be opened", csv.c_str());
    std::string line;
    std::size_t line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r')
            line.pop_back();
        if (line.find_first_not_of(" \t") == std::string::npos || line[0] == '#')
            continue;
        const std::size_t comma = line.rfind(',');
        const std::string value = comma == std::string::npos ? line : line.substr(comma + 1);
        // The C syntax whatever LC_NUMERIC says ("12.5", never "12,5": the
        // comma separates the columns); spaces around the number are allowed.
        const std::size_t first = value.find_first_not_of(" \t");
        const std::size_t last = value.find_last_not_of(" \t");
        double mm = 0;
        const bool number =
            first != std::string::npos &&
            parse_double(std::string_view(value).substr(first, last - first + 1), mm);
        if (!number) {
            if (csv_encoder_.empty() && line_no == 1)
                continue;  // a header
            raise(FLT_ERR_FORMAT, "encoder CSV '%.200s' line %zu: '%.60s' is not a number",
                  csv.c_str(), line_no, value.c_str());
        }
        const std::size_t row = csv_encoder_.size();
        if (comma != std::string::npos && row < paths_.size()) {
            std::string name = line.substr(0, line.find(','));
            name.erase(0, name.find_first_not_of(" \t\""));
            name.erase(name.find_last_not_of(" \t\"") + 1);
            if (name != base_name(paths_[row]))
                raise(FLT_ERR_FORMAT,
                      "encoder CSV '%.200s' line %zu names '%.80s', but image %zu is '%.80s'",
                      csv.c_str(), line_no, name.c_str(), row, base_name(paths_[row]).c_str());
        }
        csv_encoder_.push_back(mm);
    }
    if (csv_encoder_.size() != paths_.size())
        raise(FLT_ERR_FORMAT, "encoder CSV '%.200s' has %zu positions for %zu images", csv.c_str(),
              csv_encoder_.size(), paths_.size());
}

void image_source::open_first() {
    load(0);
    const bool wide = image_.depth() == CV_16U;
    if (!wide && option_bits_ != 0)
        raise(FLT_ERR_INVALID_ARGUMENT,
              "option 'source_image_bits' = %d, but '%.200s' has 8 bits per pixel", option_bits_,
              paths_[0].c_str());
    bits_ = wide ? (option_bits_ ? option_bits_ : 16) : 8;
    width_ = std::uint32_t(image_.cols);
    height_ = std::uint32_t(image_.rows);
}

}  // namespace

std::unique_ptr<source_impl> make_image_source(std::vector<std::string> paths,
                                               const char *encoder_csv, int image_bits) {
    auto s = std::make_unique<image_source>(std::move(paths), image_bits);
    if (encoder_csv)
        s->read_csv(encoder_csv);
    s->open_first();
    return s;
}

std::vector<std::string> list_image_files(const std::string &directory) {
    namespace fs = std::filesystem;
    std::error_code ec;
    fs::directory_iterator it(utf8_path(directory), ec);
    if (ec)
        raise(FLT_ERR_IO, "directory '%.200s' cannot be opened", directory.c_str());
    std::vector<std::string> names;
    for (; it != fs::directory_iterator(); it.increment(ec)) {
        const std::string name = utf8_string(it->path().filename());
        if (has_image_suffix(name))
            names.push_back(name);
    }
    if (ec)
        raise(FLT_ERR_IO, "directory '%.200s' cannot be read: %s", directory.c_str(),
              ec.message().c_str());
    if (names.empty())
        raise(FLT_ERR_NOT_FOUND, "directory '%.200s' holds no .png, .tif or .tiff file",
              directory.c_str());
    std::sort(names.begin(), names.end());
    std::string folder(directory);
    if (folder.back() != '/' && folder.back() != '\\')
        folder += '/';
    for (std::string &n : names)
        n.insert(0, folder);
    return names;
}

}  // namespace flt::sources
