// A frame read back from GL, and its encoding to PNG (stb_image_write) on a worker thread: a 1080p frame
// takes about 150 ms to encode here against a few to draw, so encoding must not hold the drawing back.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace stepwise::render {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  // width * height * 4 bytes, top row first
};

// PNG file contents; std::runtime_error naming stbi_write_png_to_func if it fails
std::string encode_png(const Image& image);

// FNV-1a 64 over the pixels, as 16 hex digits: a frame's identity for determinism checks
std::string pixel_hash(const Image& image);

// encodes images in order on one worker thread and hands each PNG to `write` (there, on that thread);
// finish() waits for all and rethrows the first exception a write raised. At most max_pending images wait:
// push() waits for room, so that drawing faster than encoding (14 ms a 1280 x 720 frame against 70 ms to
// encode it) does not hold every frame in memory at once
class EncodeQueue {
 public:
  static constexpr size_t max_pending = 2;
  explicit EncodeQueue(std::function<void(size_t index, const std::string& png)> write);
  ~EncodeQueue();
  EncodeQueue(const EncodeQueue&) = delete;
  EncodeQueue& operator=(const EncodeQueue&) = delete;
  void push(Image image);
  void finish();

 private:
  void work();
  std::function<void(size_t, const std::string&)> write_;
  std::mutex mutex_;
  std::condition_variable ready_, room_;
  std::deque<Image> pending_;
  size_t next_ = 0;
  bool closing_ = false;
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace stepwise::render
