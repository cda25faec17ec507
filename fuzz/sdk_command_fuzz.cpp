// sdk::parse and sdk::classify_command on arbitrary text. Properties (command.hpp):
//   classify accepts a text only if parse accepts it and to_text(parse(text)) == text;
//   the canonical text of a parsed command parses back to the same command, and is classified
//   as the command's kind.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <variant>

#include "sdk/command.hpp"

using namespace shelfcross::sdk;

namespace {

[[noreturn]] void fail(const char* what, std::string_view text, const std::string& detail) {
  std::fprintf(stderr, "sdk command: %s: '%.*s' (%s)\n", what, int(text.size()), text.data(), detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto parsed = parse(text);
  std::string why;
  const auto kind = classify_command(text, &why);

  if (const auto* err = std::get_if<ParseError>(&parsed)) {
    if (kind) fail("classify accepts what parse refuses", text, err->reason);
    if (err->reply.empty() || err->reason.empty()) fail("refusal without reply or reason", text, err->reply);
    if (why.empty()) fail("classify refuses without a reason", text, "");
    return 0;
  }
  const Command& c = std::get<Command>(parsed);
  if (c.arg_count < 0 || c.arg_count > int(c.args.size())) fail("argument count", text, std::to_string(c.arg_count));
  const std::string canonical = to_text(c);
  if (kind && canonical != text) fail("classify accepts a non-canonical text", text, canonical);
  if (kind && *kind != kind_of(c.verb)) fail("classify's kind", text, canonical);
  if (!kind && why.empty()) fail("classify refuses without a reason", text, canonical);

  const auto again = parse(canonical);
  if (const auto* err = std::get_if<ParseError>(&again)) fail("canonical text refused", canonical, err->reason);
  if (!(std::get<Command>(again) == c)) fail("canonical text parses to another command", text, canonical);
  const auto canonical_kind = classify_command(canonical, &why);
  if (!canonical_kind) fail("canonical text not classified", canonical, why);
  if (*canonical_kind != kind_of(c.verb)) fail("canonical text's kind", canonical, why);
  if (verb_text(c.verb).empty()) fail("verb text", text, canonical);
  return 0;
}
