#include "flight_sw/mission/command_pacer.hpp"

#include <cctype>

namespace shelfcross::flight_sw {

bool is_ok_reply(const std::string& text) {
  size_t b = 0, e = text.size();
  while (b < e && std::isspace(static_cast<unsigned char>(text[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1]))) --e;
  return e - b == 2 && std::tolower(static_cast<unsigned char>(text[b])) == 'o' &&
         std::tolower(static_cast<unsigned char>(text[b + 1])) == 'k';
}

}  // namespace shelfcross::flight_sw
