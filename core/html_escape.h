#pragma once
// Text for HTML and SVG, in an element's text or in a quoted attribute alike: & < > " and '
// become &amp; &lt; &gt; &quot; and &#39;; every other byte (UTF-8 included) is kept.
// Pure function: safe from any thread.
#include <string>
#include <string_view>

namespace doorbench {

std::string html_escape(std::string_view text);

}  // namespace doorbench
