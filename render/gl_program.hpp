#pragma once
// The renderer's two GL programs (flat and textured faces) and GL error checks; the context
// must be current. Both throw RenderError with GL's reason.

namespace shelfcross::render {

/// Untextured faces: each vertex's clip coordinates and its face's colour.
unsigned int link_flat_program();
/// Marker faces: the colour times the atlas's texel (texture unit 0, uniform "atlas").
unsigned int link_textured_program();
/// Throws RenderError naming `where` if GL has recorded an error.
void check_gl(const char* where);

}  // namespace shelfcross::render
