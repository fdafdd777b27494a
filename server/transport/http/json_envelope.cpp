#include "server/transport/http/json_envelope.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/type.pb.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/type_resolver.h>
#include <google/protobuf/util/type_resolver_util.h>

#include <map>
#include <memory>
#include <mutex>

#include "server/common/limits.h"

namespace sim4cv::transport {
namespace {

namespace pb = google::protobuf;

// protobuf's JsonStringToMessage and MessageToJsonString go through a
// TypeResolver that rebuilds a google.protobuf.Type (every field, its name,
// JSON name and type URL) from the descriptors for each message type a call
// meets, the Envelope's dozens of fields first; that was most of the cost of
// a small message. The types never change in a running daemon, so they are
// built once and copied out on later calls. Shared by every session's thread.
class CachingTypeResolver : public pb::util::TypeResolver {
 public:
  CachingTypeResolver()
      : resolver_(pb::util::NewTypeResolverForDescriptorPool(kUrlPrefix, pb::DescriptorPool::generated_pool())) {}

  pb::util::Status ResolveMessageType(const std::string& type_url, pb::Type* type) override {
    return Resolve(types_, type_url, type, &pb::util::TypeResolver::ResolveMessageType);
  }
  pb::util::Status ResolveEnumType(const std::string& type_url, pb::Enum* enum_type) override {
    return Resolve(enums_, type_url, enum_type, &pb::util::TypeResolver::ResolveEnumType);
  }

  static constexpr const char* kUrlPrefix = "type.googleapis.com";

 private:
  // Unknown URLs are not cached: a client cannot grow the cache (the JSON
  // mapping resolves only types the Envelope's descriptors name anyway).
  template <typename T>
  pb::util::Status Resolve(std::map<std::string, T>& cache, const std::string& url, T* out,
                           pb::util::Status (pb::util::TypeResolver::*resolve)(const std::string&, T*)) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto found = cache.find(url);
    if (found == cache.end()) {
      T resolved;
      pb::util::Status status = (resolver_.get()->*resolve)(url, &resolved);
      if (!status.ok()) return status;
      found = cache.emplace(url, std::move(resolved)).first;
    }
    *out = found->second;
    return pb::util::Status();
  }

  std::unique_ptr<pb::util::TypeResolver> resolver_;
  std::mutex mutex_;
  std::map<std::string, pb::Type> types_;
  std::map<std::string, pb::Enum> enums_;
};

CachingTypeResolver& Resolver() {
  static auto* resolver = new CachingTypeResolver();  // never destroyed: sessions may outlive statics
  return *resolver;
}

const std::string& EnvelopeTypeUrl() {
  static const std::string url =
      std::string(CachingTypeResolver::kUrlPrefix) + "/" + proto::Envelope::descriptor()->full_name();
  return url;
}

}  // namespace

// The same steps as protobuf's JsonStringToMessage (JSON to the binary form
// by the resolver's types, then the binary parse), with the cached types.
std::string EnvelopeFromJson(std::string_view text, proto::Envelope& envelope) {
  envelope.Clear();
  pb::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field is the client's bug: name it
  std::string binary;
  auto status = pb::util::JsonToBinaryString(&Resolver(), EnvelopeTypeUrl(), pb::StringPiece(text.data(), text.size()),
                                             &binary, options);
  if (status.ok() && !envelope.ParseFromString(binary)) {
    status = pb::util::InvalidArgumentError("JSON transcoder produced invalid protobuf output.");
  }
  if (status.ok()) return {};
  // protobuf's message can quote the client's text at length: bound what we echo.
  std::string why(status.message());
  constexpr std::size_t kMaxReasonBytes = 4 * limits::kQuotedBytes;
  if (why.size() > kMaxReasonBytes) why = why.substr(0, kMaxReasonBytes) + "...";
  return why.empty() ? "not a JSON Envelope" : why;
}

void EnvelopeToJson(const proto::Envelope& envelope, std::string& out) {
  out.clear();
  pb::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  pb::util::BinaryToJsonString(&Resolver(), EnvelopeTypeUrl(), envelope.SerializeAsString(), &out, options);
}

}  // namespace sim4cv::transport
