#include "image.hpp"

#include <stb_image_write.h>

#include <fmt/format.h>

#include <stdexcept>

namespace stepwise::render {

std::string encode_png(const Image& image) {
  std::string bytes;
  const auto append = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), static_cast<size_t>(size));
  };
  if (!stbi_write_png_to_func(append, &bytes, image.width, image.height, 4, image.rgba.data(), 4 * image.width))
    throw std::runtime_error(fmt::format("stbi_write_png_to_func ({} x {}) returned 0", image.width, image.height));
  return bytes;
}

std::string pixel_hash(const Image& image) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (const std::uint8_t b : image.rgba) h = (h ^ b) * 0x100000001b3ull;
  return fmt::format("{:016x}", h);
}

EncodeQueue::EncodeQueue(std::function<void(size_t, const std::string&)> write) : write_(std::move(write)), worker_([this] { work(); }) {}

EncodeQueue::~EncodeQueue() {
  {
    std::lock_guard lock(mutex_);
    closing_ = true;
  }
  ready_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void EncodeQueue::push(Image image) {
  {
    std::unique_lock lock(mutex_);
    room_.wait(lock, [&] { return pending_.size() < max_pending; });
    pending_.push_back(std::move(image));
  }
  ready_.notify_all();
}

void EncodeQueue::finish() {
  {
    std::lock_guard lock(mutex_);
    closing_ = true;
  }
  ready_.notify_all();
  if (worker_.joinable()) worker_.join();
  if (error_) std::rethrow_exception(error_);
}

void EncodeQueue::work() {
  for (;;) {
    Image image;
    {
      std::unique_lock lock(mutex_);
      ready_.wait(lock, [&] { return closing_ || !pending_.empty(); });
      if (pending_.empty()) return;
      image = std::move(pending_.front());
      pending_.pop_front();
    }
    room_.notify_all();
    // after a failure the rest are dropped: the first error is the one to report
    if (error_) continue;
    try {
      write_(next_++, encode_png(image));
    } catch (...) {
      error_ = std::current_exception();
    }
  }
}

}  // namespace stepwise::render
