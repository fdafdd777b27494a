#include "server/transport/http/json_envelope.h"

#include <google/protobuf/util/json_util.h>

#include "server/common/limits.h"

namespace sim4cv::transport {

std::string EnvelopeFromJson(std::string_view text, proto::Envelope& envelope) {
  envelope.Clear();
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // a misspelt field is the client's bug: name it
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(text.data(), text.size()), &envelope, options);
  if (status.ok()) return {};
  // protobuf's message can quote the client's text at length: bound what we echo.
  std::string why(status.message());
  constexpr std::size_t kMaxReasonBytes = 4 * limits::kQuotedBytes;
  if (why.size() > kMaxReasonBytes) why = why.substr(0, kMaxReasonBytes) + "...";
  return why.empty() ? "not a JSON Envelope" : why;
}

void EnvelopeToJson(const proto::Envelope& envelope, std::string& out) {
  out.clear();
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  google::protobuf::util::MessageToJsonString(envelope, &out, options);
}

}  // namespace sim4cv::transport
