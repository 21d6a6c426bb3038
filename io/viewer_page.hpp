#pragma once
// The viewer page (docs/viewer.md): one self-contained HTML file (viewer/page.html with
// three.js, viewer/viewer.js and the .glb embedded, base64) that draws and relights a glb from
// file:// with no network. The page's files are compiled into the library (viewer/embed.py).

#include <string>

namespace lambert {

/// The page's HTML for the glb `glb` (its bytes), titled `title` (HTML-escaped).
std::string viewer_page_html(const std::string& glb, const std::string& title);

/// Writes viewer_page_html to `path` atomically. Throws IoError.
void write_viewer_page(const std::string& path, const std::string& glb, const std::string& title);

}  // namespace lambert
