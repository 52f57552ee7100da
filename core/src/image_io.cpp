#include "epipole/core/image_io.hpp"

#include <jpeglib.h>
#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "epipole/core/error.hpp"

// libpng and libjpeg report errors by longjmp. Each setjmp below sits in a function whose own
// locals are never modified after it, and every C++ object that must be destroyed lives in the
// caller's frame, so a jump can never skip a destructor or observe an indeterminate value.

namespace epipole {
namespace {

using std::filesystem::path;

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

FilePtr open_file(const path& file, const char* mode) {
  FilePtr f(std::fopen(file.c_str(), mode));
  require(f != nullptr, file.string(), ": cannot open: ", std::strerror(errno));
  return f;
}

enum class Format { png, jpeg, pgm, unknown };

// What a header claims is checked before the image is allocated: a few bytes must not ask for
// gigabytes.
void check_size(const path& file, const char* format, long long width, long long height) {
  require(width * height <= kMaxImagePixels, file.string(), ": ", format, " size ", width, "x",
          height, " is more than the ", kMaxImagePixels, " pixels an image may have");
}

Format sniff(std::FILE* f) {
  unsigned char magic[8] = {};
  const std::size_t n = std::fread(magic, 1, sizeof magic, f);
  std::rewind(f);
  if (n >= 8 && png_sig_cmp(magic, 0, 8) == 0) return Format::png;
  if (n >= 3 && magic[0] == 0xFF && magic[1] == 0xD8 && magic[2] == 0xFF) return Format::jpeg;
  if (n >= 2 && magic[0] == 'P' && magic[1] == '5') return Format::pgm;
  return Format::unknown;
}

// ---------------------------------------------------------------- PNG

struct PngReader {
  png_structp png = nullptr;
  png_infop info = nullptr;
  char message[256] = "unknown error";
  int width = 0;
  int height = 0;
  int depth = 0;  // bits per sample as read
  ~PngReader() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

[[noreturn]] void on_png_error(png_structp png, png_const_charp message) {
  auto* context = static_cast<char*>(png_get_error_ptr(png));
  std::snprintf(context, 256, "%s", message);
  png_longjmp(png, 1);
}

void on_png_warning(png_structp, png_const_charp) {}

// Reads the header and sets the transforms that give one channel of at most `bits` bits (an 8-bit
// file read for 16 bits stays 8-bit: its samples keep their values).
bool png_read_header(PngReader& r, std::FILE* f, int bits) {
  if (setjmp(png_jmpbuf(r.png))) return false;
  png_init_io(r.png, f);
  png_read_info(r.png, r.info);
  const int color = png_get_color_type(r.png, r.info);
  const int depth = png_get_bit_depth(r.png, r.info);
  if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(r.png);
  if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(r.png);
  if (png_get_valid(r.png, r.info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(r.png);
  if (bits == 8) png_set_strip_16(r.png);
  if (bits == 16 && depth == 16) png_set_swap(r.png);  // PNG is big-endian; ours are native
  png_set_strip_alpha(r.png);
  if (color & PNG_COLOR_MASK_COLOR) png_set_rgb_to_gray(r.png, 1, 0.299, 0.587);
  png_read_update_info(r.png, r.info);
  r.width = static_cast<int>(png_get_image_width(r.png, r.info));
  r.height = static_cast<int>(png_get_image_height(r.png, r.info));
  r.depth = png_get_bit_depth(r.png, r.info);
  return png_get_channels(r.png, r.info) == 1;
}

bool png_read_pixels(PngReader& r, png_bytepp rows) {
  if (setjmp(png_jmpbuf(r.png))) return false;
  png_read_image(r.png, rows);
  png_read_end(r.png, nullptr);
  return true;
}

template <typename T>
Image<T> read_png(std::FILE* f, const path& file) {
  PngReader r;
  r.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, r.message, on_png_error, on_png_warning);
  require(r.png != nullptr, file.string(), ": out of memory");
  r.info = png_create_info_struct(r.png);
  require(r.info != nullptr, file.string(), ": out of memory");
  if (!png_read_header(r, f, 8 * static_cast<int>(sizeof(T)))) {
    throw Error(cat(file.string(), ": bad PNG: ", r.message));
  }
  check_size(file, "PNG", r.width, r.height);
  Image<T> image(r.width, r.height);
  std::vector<png_bytep> rows(static_cast<std::size_t>(r.height));
  if (sizeof(T) == 2 && r.depth == 8) {
    // 8-bit samples for a 16-bit image: read, then widened with their values kept.
    GrayImage narrow(r.width, r.height);
    for (int y = 0; y < r.height; ++y) rows[y] = narrow.view().row(y);
    if (!png_read_pixels(r, rows.data())) {
      throw Error(cat(file.string(), ": bad PNG: ", r.message));
    }
    for (int y = 0; y < r.height; ++y) {
      std::copy_n(narrow.view().row(y), r.width, image.view().row(y));
    }
    return image;
  }
  for (int y = 0; y < r.height; ++y) rows[y] = reinterpret_cast<png_bytep>(image.view().row(y));
  if (!png_read_pixels(r, rows.data())) throw Error(cat(file.string(), ": bad PNG: ", r.message));
  return image;
}

struct PngWriter {
  png_structp png = nullptr;
  png_infop info = nullptr;
  char message[256] = "unknown error";
  ~PngWriter() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

bool png_write(PngWriter& w, std::FILE* f, int width, int height, int depth, int color,
               png_bytepp rows) {
  if (setjmp(png_jmpbuf(w.png))) return false;
  png_init_io(w.png, f);
  png_set_IHDR(w.png, w.info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height),
               depth, color, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_write_info(w.png, w.info);
  if (depth == 16) png_set_swap(w.png);
  png_write_image(w.png, rows);
  png_write_end(w.png, nullptr);
  return true;
}

template <typename T>
void write_png(const path& file, ImageView<const T> image, int depth, int color) {
  require(!image.empty(), file.string(), ": cannot write an empty image");
  FilePtr f = open_file(file, "wb");
  PngWriter w;
  w.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, w.message, on_png_error, on_png_warning);
  require(w.png != nullptr, file.string(), ": out of memory");
  w.info = png_create_info_struct(w.png);
  require(w.info != nullptr, file.string(), ": out of memory");
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.height()));
  for (int y = 0; y < image.height(); ++y) {
    // libpng's API takes non-const rows but does not write to them when encoding.
    rows[y] = reinterpret_cast<png_bytep>(const_cast<T*>(image.row(y)));
  }
  if (!png_write(w, f.get(), image.width(), image.height(), depth, color, rows.data())) {
    throw Error(cat(file.string(), ": cannot write PNG: ", w.message));
  }
  require(std::fflush(f.get()) == 0, file.string(), ": write failed: ", std::strerror(errno));
}

// ---------------------------------------------------------------- JPEG

struct JpegErrors {
  jpeg_error_mgr manager{};
  std::jmp_buf jump{};
  char message[JMSG_LENGTH_MAX] = "unknown error";
};

struct JpegReader {
  jpeg_decompress_struct info{};
  JpegErrors errors;
  bool created = false;
  ~JpegReader() {
    if (created) jpeg_destroy_decompress(&info);
  }
};

// The reader's errors come through client_data (jpeg_create_decompress keeps it), not by a cast
// of info->err to the struct that holds it, which would ask for a stricter alignment on armhf.
[[noreturn]] void on_jpeg_error(j_common_ptr info) {
  auto* errors = static_cast<JpegErrors*>(info->client_data);
  (*info->err->format_message)(info, errors->message);
  std::longjmp(errors->jump, 1);
}

void on_jpeg_message(j_common_ptr, int) {}

bool jpeg_read_header_gray(JpegReader& r, std::FILE* f) {
  r.info.err = jpeg_std_error(&r.errors.manager);
  r.info.client_data = &r.errors;
  r.errors.manager.error_exit = on_jpeg_error;
  r.errors.manager.emit_message = on_jpeg_message;
  if (setjmp(r.errors.jump)) return false;
  jpeg_create_decompress(&r.info);
  r.created = true;
  jpeg_stdio_src(&r.info, f);
  jpeg_read_header(&r.info, TRUE);
  // Before jpeg_start_decompress sets up its buffers (whole-image ones for progressive files).
  if (static_cast<long long>(r.info.image_width) * r.info.image_height > kMaxImagePixels) {
    std::snprintf(r.errors.message, sizeof r.errors.message,
                  "size %ux%u is more than the %lld pixels an image may have",
                  static_cast<unsigned>(r.info.image_width),
                  static_cast<unsigned>(r.info.image_height), kMaxImagePixels);
    return false;
  }
  r.info.out_color_space = JCS_GRAYSCALE;  // libjpeg converts, as OpenCV's decoder asks it to
  jpeg_start_decompress(&r.info);
  return r.info.output_components == 1;
}

bool jpeg_read_rows(JpegReader& r, MutableGrayView image) {
  if (setjmp(r.errors.jump)) return false;
  while (r.info.output_scanline < r.info.output_height) {
    JSAMPROW row = image.row(static_cast<int>(r.info.output_scanline));
    jpeg_read_scanlines(&r.info, &row, 1);
  }
  jpeg_finish_decompress(&r.info);
  return true;
}

GrayImage read_jpeg(std::FILE* f, const path& file) {
  JpegReader r;
  if (!jpeg_read_header_gray(r, f)) {
    throw Error(cat(file.string(), ": bad JPEG: ", r.errors.message));
  }
  check_size(file, "JPEG", r.info.output_width, r.info.output_height);
  GrayImage image(static_cast<int>(r.info.output_width), static_cast<int>(r.info.output_height));
  if (!jpeg_read_rows(r, image.view())) {
    throw Error(cat(file.string(), ": bad JPEG: ", r.errors.message));
  }
  return image;
}

// ---------------------------------------------------------------- PGM / PPM

// Reads one header number of a binary PNM file, skipping white space and # comments.
int pnm_number(std::FILE* f, const path& file, const char* what) {
  int c = std::fgetc(f);
  while (c == '#' || std::isspace(c)) {
    if (c == '#') {
      while (c != '\n' && c != EOF) c = std::fgetc(f);
    }
    c = std::fgetc(f);
  }
  long value = 0;
  bool any = false;
  while (c >= '0' && c <= '9') {
    value = value * 10 + (c - '0');
    require(value <= 1'000'000, file.string(), ": PGM ", what, " is too large");
    any = true;
    c = std::fgetc(f);
  }
  require(any && (c == EOF || std::isspace(c)), file.string(), ": PGM header has a bad ", what);
  return static_cast<int>(value);
}

// Reads a P5 file; samples wider than T keep their high byte.
template <typename T>
Image<T> read_pgm(std::FILE* f, const path& file) {
  std::fseek(f, 2, SEEK_SET);
  const int width = pnm_number(f, file, "width");
  const int height = pnm_number(f, file, "height");
  const int maxval = pnm_number(f, file, "maximum value");
  require(width > 0 && height > 0, file.string(), ": PGM size ", width, "x", height, " is empty");
  require(maxval > 0 && maxval < 65536, file.string(), ": PGM maximum value ", maxval,
          " is out of range");
  const std::size_t sample_bytes = maxval < 256 ? 1 : 2;
  check_size(file, "PGM", width, height);
  // The header's last whitespace byte is read with the maximum value: the samples follow, and
  // the file must hold them all.
  const long data_start = std::ftell(f);
  std::fseek(f, 0, SEEK_END);
  const long file_end = std::ftell(f);
  const auto needed = static_cast<long long>(sample_bytes) * width * height;
  require(data_start > 0 && file_end - data_start >= needed, file.string(),
          ": PGM data ends early: ", width, "x", height, " samples need ", needed,
          " bytes, the file has ", std::max(0L, file_end - data_start), " after its header");
  std::fseek(f, data_start, SEEK_SET);
  Image<T> image(width, height);
  std::vector<unsigned char> line(sample_bytes * static_cast<std::size_t>(width));
  for (int y = 0; y < height; ++y) {
    require(std::fread(line.data(), 1, line.size(), f) == line.size(), file.string(),
            ": PGM data ends at row ", y, " of ", height);
    T* out = image.view().row(y);
    for (int x = 0; x < width; ++x) {
      const unsigned sample = sample_bytes == 1 ? line[x] : (line[2 * x] << 8) | line[2 * x + 1];
      if constexpr (sizeof(T) == 1) {
        out[x] = static_cast<T>(sample_bytes == 1 ? sample : sample >> 8);
      } else {
        out[x] = static_cast<T>(sample);
      }
    }
  }
  return image;
}

template <typename T>
void write_pnm(const path& file, ImageView<const T> image, const char* magic, int channels,
               int maxval) {
  require(!image.empty(), file.string(), ": cannot write an empty image");
  FilePtr f = open_file(file, "wb");
  std::fprintf(f.get(), "%s\n%d %d\n%d\n", magic, image.width(), image.height(), maxval);
  const std::size_t sample_bytes = maxval < 256 ? 1 : 2;
  std::vector<unsigned char> line(sample_bytes * static_cast<std::size_t>(image.width()) *
                                  static_cast<std::size_t>(channels));
  for (int y = 0; y < image.height(); ++y) {
    if constexpr (sizeof(T) == 2) {
      for (int x = 0; x < image.width(); ++x) {
        line[2 * x] = static_cast<unsigned char>(image.row(y)[x] >> 8);
        line[2 * x + 1] = static_cast<unsigned char>(image.row(y)[x] & 0xFF);
      }
    } else {
      std::memcpy(line.data(), image.row(y), line.size());
    }
    require(std::fwrite(line.data(), 1, line.size(), f.get()) == line.size(), file.string(),
            ": write failed: ", std::strerror(errno));
  }
  require(std::fflush(f.get()) == 0, file.string(), ": write failed: ", std::strerror(errno));
}

// ---------------------------------------------------------------- dispatch

std::string lower_extension(const path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

template <typename T>
Image<T> load(const path& file) {
  FilePtr f = open_file(file, "rb");
  switch (sniff(f.get())) {
    case Format::png:
      return read_png<T>(f.get(), file);
    case Format::pgm:
      return read_pgm<T>(f.get(), file);
    case Format::jpeg:
      if constexpr (sizeof(T) == 1) {
        return read_jpeg(f.get(), file);
      } else {
        const GrayImage narrow = read_jpeg(f.get(), file);
        Image<T> wide(narrow.width(), narrow.height());
        for (int y = 0; y < narrow.height(); ++y) {
          std::copy_n(narrow.view().row(y), narrow.width(), wide.view().row(y));
        }
        return wide;
      }
    case Format::unknown:
      break;
  }
  throw Error(cat(file.string(), ": not a PNG, JPEG or binary PGM file"));
}

}  // namespace

GrayImage load_gray(const path& file) {
  return load<std::uint8_t>(file);
}

Image<std::uint16_t> load_gray16(const path& file) {
  return load<std::uint16_t>(file);
}

void save_image(const path& file, ImageView<const std::uint8_t> image) {
  const std::string ext = lower_extension(file);
  if (ext == ".png") return write_png(file, image, 8, PNG_COLOR_TYPE_GRAY);
  if (ext == ".pgm") return write_pnm(file, image, "P5", 1, 255);
  throw Error(cat(file.string(), ": unknown image extension (expected .png or .pgm)"));
}

void save_image(const path& file, ImageView<const std::uint16_t> image) {
  const std::string ext = lower_extension(file);
  if (ext == ".png") return write_png(file, image, 16, PNG_COLOR_TYPE_GRAY);
  if (ext == ".pgm") return write_pnm(file, image, "P5", 1, 65535);
  throw Error(cat(file.string(), ": unknown image extension (expected .png or .pgm)"));
}

void save_image(const path& file, ImageView<const Rgb8> image) {
  static_assert(sizeof(Rgb8) == 3);
  const std::string ext = lower_extension(file);
  if (ext == ".png") return write_png(file, image, 8, PNG_COLOR_TYPE_RGB);
  if (ext == ".ppm") return write_pnm(file, image, "P6", 3, 255);
  throw Error(cat(file.string(), ": unknown image extension (expected .png or .ppm)"));
}

}  // namespace epipole
