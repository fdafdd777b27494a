#include "server/codec/jpeg.h"

// clang-format off
#include <cstdio>  // before jpeglib.h, which needs FILE declared
#include <jpeglib.h>
// clang-format on

#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace sim4cv::codec {
namespace {

// libjpeg reports errors by calling error_exit, which must not return; a C++
// exception carries the message out instead of exit().
[[noreturn]] void ThrowError(j_common_ptr info) {
  char message[JMSG_LENGTH_MAX];
  (*info->err->format_message)(info, message);
  throw std::runtime_error(std::string("JPEG effect: ") + message);
}

}  // namespace

std::span<const uint8_t> JpegEncoder::Encode(const uint8_t* rgb, uint32_t width, uint32_t height, int quality) {
  const std::size_t row_bytes = static_cast<std::size_t>(width) * 3;
  // Larger than any JPEG of the image (raw size plus headers), so libjpeg never reallocates it.
  if (encoded_.size() < row_bytes * height + 4096) encoded_.resize(row_bytes * height + 4096);

  jpeg_error_mgr errors{};
  jpeg_compress_struct encoder{};
  encoder.err = jpeg_std_error(&errors);
  errors.error_exit = ThrowError;
  unsigned char* buffer = encoded_.data();
  unsigned long size = encoded_.size();
  jpeg_create_compress(&encoder);
  try {
    jpeg_mem_dest(&encoder, &buffer, &size);
    encoder.image_width = width;
    encoder.image_height = height;
    encoder.input_components = 3;
    encoder.in_color_space = JCS_RGB;
    jpeg_set_defaults(&encoder);
    jpeg_set_quality(&encoder, quality, TRUE);
    jpeg_start_compress(&encoder, TRUE);
    while (encoder.next_scanline < height) {
      // libjpeg's row type is not const; it only reads the rows it is given.
      JSAMPROW row = const_cast<uint8_t*>(rgb) + encoder.next_scanline * row_bytes;
      jpeg_write_scanlines(&encoder, &row, 1);
    }
    jpeg_finish_compress(&encoder);
  } catch (...) {
    jpeg_destroy_compress(&encoder);
    throw;
  }
  jpeg_destroy_compress(&encoder);
  if (buffer != encoded_.data()) std::free(buffer);  // cannot happen: the buffer holds the raw image
  if (buffer != encoded_.data()) throw std::runtime_error("JPEG effect: encoded image outgrew its buffer");
  return {encoded_.data(), static_cast<std::size_t>(size)};
}

void JpegRoundTrip::Apply(uint8_t* rgb, uint32_t width, uint32_t height, int quality) {
  const std::size_t row_bytes = static_cast<std::size_t>(width) * 3;
  const std::span<const uint8_t> encoded = encoder_.Encode(rgb, width, height, quality);

  jpeg_error_mgr errors{};
  jpeg_decompress_struct decoder{};
  decoder.err = jpeg_std_error(&errors);
  errors.error_exit = ThrowError;
  jpeg_create_decompress(&decoder);
  try {
    jpeg_mem_src(&decoder, encoded.data(), static_cast<unsigned long>(encoded.size()));
    jpeg_read_header(&decoder, TRUE);
    decoder.out_color_space = JCS_RGB;
    decoder.dct_method = JDCT_ISLOW;  // exact integer DCT: the same on every machine
    jpeg_start_decompress(&decoder);
    while (decoder.output_scanline < height) {
      JSAMPROW row = rgb + decoder.output_scanline * row_bytes;
      jpeg_read_scanlines(&decoder, &row, 1);
    }
    jpeg_finish_decompress(&decoder);
  } catch (...) {
    jpeg_destroy_decompress(&decoder);
    throw;
  }
  jpeg_destroy_decompress(&decoder);
}

}  // namespace sim4cv::codec
