// The viewer's page (host/view/viewer.html: HTML, CSS and JavaScript in one file), embedded at build time.
#pragma once

#include <string>

namespace mipnerf::view {

const std::string& page_html();

}  // namespace mipnerf::view
