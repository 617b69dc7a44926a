// Text from a hostile input as an error line can show it: what the user sees is what the input
// holds. A control character (a "\r" of a CRLF file, a NUL, an escape sequence) or a byte outside
// ASCII would otherwise be invisible, or rewrite the terminal, in a line that then looks valid.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace whiskeye {

// `text` in single quotes: printable ASCII as it is (a quote or backslash as \' \\), "\r", "\t" and
// "\n" so, any other byte as \xNN; of a text longer than `max_chars`, its first max_chars and
// "... (N bytes)".
std::string printable(std::string_view text, std::size_t max_chars = 60);

}  // namespace whiskeye
