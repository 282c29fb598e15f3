#pragma once
/// @file surface_readers.hpp
/// @brief Triangle surface readers (OBJ, STL, OFF) and writers for round trips.

#include <corocontact/core/surface_mesh.hpp>

#include <filesystem>

namespace coro {

/// Reads a triangle surface, choosing the format by extension (case-insensitive):
/// - `.obj`: `v x y z` and `f` lines; face corners may be `i`, `i/t`, `i//n` or `i/t/n` (only
///   `i` is used), negative indices count back from the last vertex defined so far, faces with
///   more than 3 corners are fan-triangulated (v0, vk, vk+1); `vt`, `vn`, `g`, `o`, `s`,
///   `usemtl`, `mtllib`, `l`, `p`, free-form statements and `#` comments are ignored; any
///   other statement is an error.
/// - `.stl`: ASCII (`solid`, `facet normal`, `outer loop`, 3 × `vertex`, `endloop`,
///   `endfacet`, `endsolid`; several solids may follow each other) or binary (80-byte header,
///   little-endian uint32 triangle count, 50-byte records). A file whose size is exactly
///   84 + 50·count is binary even if its header starts with "solid"; otherwise a file that
///   starts with "solid" and holds no control characters is ASCII. Facet normals are ignored.
///   STL stores every triangle's corners separately: corners with identical coordinates
///   (compared as doubles, so −0 = +0) are merged into one vertex, numbered in order of first
///   appearance.
/// - `.off`: optional `OFF` header (also `COFF`, `NOFF`, `CNOFF`, `STOFF`..., whose extra
///   per-vertex values are ignored), a counts line `#V #F [#E]`, #V vertex lines, #F face lines
///   `n i0 ... in-1 [colour]` with n ≥ 3 and 0-based indices, fan-triangulated; `#` starts a
///   comment.
///
/// The result is validated: coordinates finite, indices in range, no face that repeats a
/// vertex, at least one face, at most 2^31−1 vertices. Counts given in a file are never
/// trusted for allocation: an OFF header is checked line by line as its items are read, a
/// binary STL count against the file size. Unused vertices (OBJ, OFF) are kept.
/// @param[in] path  a `.obj`, `.stl` or `.off` file
/// @return vertices (#V×3) and faces (#F×3) with the file's orientation
/// @throws InputError for a missing or unreadable file, an unknown extension or malformed
///         input; text formats say "path:line: expected ..., found ...", binary STL names the
///         triangle and its byte offset
SurfaceMesh read_surface(const std::filesystem::path& path);

/// Writes a surface as Wavefront OBJ (`v` lines with the shortest representation that reads
/// back to the same double, `f` lines with 1-based indices).
/// @param[in] path     file to create or overwrite
/// @param[in] surface  vertices #V×3, faces #F×3 with indices in [0, #V)
/// @throws OutputError if the file cannot be written (core/atomic_file.hpp: whole or not at all)
void write_obj(const std::filesystem::path& path, const SurfaceMesh& surface);

/// Writes a surface as OFF (`OFF`, `#V #F 0`, vertices with the shortest round-trip
/// representation, faces `3 i j k` with 0-based indices).
/// @param[in] path     file to create or overwrite
/// @param[in] surface  vertices #V×3, faces #F×3 with indices in [0, #V)
/// @throws OutputError if the file cannot be written (core/atomic_file.hpp: whole or not at all)
void write_off(const std::filesystem::path& path, const SurfaceMesh& surface);

/// Writes a surface as STL, one facet per face with its unit normal ((x1−x0)×(x2−x0)
/// normalised; zero for a zero-area face).
/// @param[in] path     file to create or overwrite
/// @param[in] surface  vertices #V×3, faces #F×3 with indices in [0, #V)
/// @param[in] binary   true: binary STL (80-byte header that does not start with "solid",
///                     coordinates rounded to float); false: ASCII STL with the shortest
///                     round-trip representation of each double (exact)
/// @throws OutputError if the file cannot be written (core/atomic_file.hpp: whole or not at
///         all); InputError if (binary) a coordinate is beyond the range of float
void write_stl(const std::filesystem::path& path, const SurfaceMesh& surface, bool binary);

} // namespace coro
