#include "polrig/background_writer.h"

#include <utility>

namespace polrig {

BackgroundWriter::~BackgroundWriter() {
  if (pending_.valid()) pending_.wait();
}

void BackgroundWriter::submit(std::function<void()> write) {
  finish();
  pending_ = std::async(std::launch::async, std::move(write));
}

void BackgroundWriter::finish() {
  if (pending_.valid()) pending_.get();
}

}  // namespace polrig
