#include "stream_input.hpp"

#include <stdexcept>
#include <string>

#include <mrpt/io/CStream.h>
#include <mrpt/serialization/CArchive.h>

#include "rtog/mrpt/CRTreeOccupancyGridMap.h"
#include "rtog/mrpt/register_classes.h"
#include "gzip.hpp"

namespace rtog {
namespace {

/// A CStream over a std::istream that reads forward only; `bytesLeft()` drains the rest.
class ForwardInput : public mrpt::io::CStream {
 public:
  size_t Write(const void*, size_t) override { throw std::logic_error("ForwardInput: read only"); }
  uint64_t Seek(int64_t, mrpt::io::CStream::TSeekOrigin) override { throw std::logic_error("ForwardInput: no seek"); }
  uint64_t getTotalBytesCount() const override { return 0; }
  virtual bool truncated() const { return false; }
  virtual std::uint64_t bytesLeft() = 0;

 protected:
  static std::uint64_t drain(std::istream& in) {
    std::uint64_t left = 0;
    char scratch[1 << 14];
    while (in.read(scratch, sizeof(scratch)) || in.gcount() > 0) left += static_cast<std::uint64_t>(in.gcount());
    return left;
  }
};

class PlainInput : public ForwardInput {
 public:
  explicit PlainInput(std::istream& in) : in_(in) {}
  size_t Read(void* buf, size_t n) override {
    in_.read(static_cast<char*>(buf), static_cast<std::streamsize>(n));
    read_ += static_cast<std::uint64_t>(in_.gcount());
    return static_cast<size_t>(in_.gcount());
  }
  uint64_t getPosition() const override { return read_; }
  std::uint64_t bytesLeft() override { return drain(in_); }

 private:
  std::istream& in_;
  std::uint64_t read_ = 0;
};

/// A gzip stream inflated as it is read.
class GzipInput : public ForwardInput {
 public:
  explicit GzipInput(std::istream& in) : in_(in), z_(in) {}

  size_t Read(void* buf, size_t n) override { return z_.read(buf, n); }
  uint64_t getPosition() const override { return z_.inflated(); }
  bool truncated() const override { return z_.truncated(); }
  /// The rest of the inflated data, then what follows the gzip member.
  std::uint64_t bytesLeft() override { return z_.bytesLeft() + drain(in_); }

 private:
  std::istream& in_;
  gzip::Inflater z_;
};

}  // namespace

std::shared_ptr<CRTreeOccupancyGridMap> readMapStream(std::istream& in) {
  const int first = in.peek();
  if (first == std::char_traits<char>::eof()) throw std::runtime_error("the file is empty");
  // Peeked, not seeked: a pipe cannot seek. A gzip member starts with 0x1f; anything else is
  // read as a plain CArchive (as CFileGZInputStream reads a file that is not compressed).
  std::unique_ptr<ForwardInput> src;
  if (gzip::startsMember(first)) src = std::make_unique<GzipInput>(in);
  else src = std::make_unique<PlainInput>(in);
  registerMrptClasses();  // ReadObject finds the class by name in MRPT's registry
  auto ar = mrpt::serialization::archiveFrom(*src);
  mrpt::serialization::CSerializable::Ptr obj;
  try {
    obj = ar.ReadObject();
  } catch (const std::exception&) {
    if (src->truncated()) throw std::runtime_error("truncated gzip stream (the file ends early)");
    throw;
  }
  auto m = std::dynamic_pointer_cast<CRTreeOccupancyGridMap>(obj);
  if (!m)
    throw std::runtime_error("holds a " + std::string(obj ? obj->GetRuntimeClass()->className : "null object") +
                             ", not an rtog::CRTreeOccupancyGridMap");
  if (const std::uint64_t n = src->bytesLeft())
    throw std::runtime_error(std::to_string(n) + " trailing byte" + (n == 1 ? "" : "s") +
                             " after the map (a damaged file, or not one map?)");
  return m;
}

}  // namespace rtog
