// The C ABI between hrtao-occt (Rust) and bridge.cpp (OpenCASCADE). Plain C types only.
#pragma once
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct hr_callbacks {
  void* ctx;
  // Progress in [0, 1] of `stage`; a non-zero return asks OCCT to stop (user break).
  int (*progress)(void* ctx, double fraction, const char* stage);
  // A unique part (one shape definition), tessellated once; `part` counts from 0.
  void (*part)(void* ctx, int32_t part, const char* name);
  // One primitive of `part`: triangles of one colour. `normals` holds one unit surface normal per vertex (3 floats
  // each, the side the triangles wind toward: out of a solid). `rgba` is NULL without colour; `face_color` is 1
  // when the colour was set on the part's faces (it then wins over an occurrence's colour).
  void (*primitive)(void* ctx, int32_t part, const float* positions, const float* normals, size_t vertex_count,
                    const uint32_t* indices, size_t index_count, const float* rgba, int32_t face_color);
  // One node of the product structure, in pre-order. `parent` is -1 for a root, `part` -1 for an assembly
  // (or a part without triangles). `world` is the column-major 4x4 placement in file coordinates; `rgba`
  // the nearest colour set on this occurrence or an enclosing one (NULL if none). Returns the node id.
  int32_t (*node)(void* ctx, int32_t parent, const char* name, int32_t part, const double* world,
                  const float* rgba, int32_t visible);
} hr_callbacks;

typedef struct hr_tessellation {
  // Linear deflection as a fraction of each part's bounding-box diagonal (0 = use `absolute`).
  double relative;
  // Linear deflection in model units when `relative` is 0.
  double absolute;
  // Angular deflection in radians.
  double angular;
} hr_tessellation;

typedef struct hr_units {
  // Metres per unit of the coordinates handed back (OCCT converts to its session unit, millimetres).
  double model_m;
  // Metres per unit the file declares, 0 if it declares none.
  double file_m;
} hr_units;

// Reads a STEP (format 0) or IGES (format 1) file and reports parts, primitives and nodes. Returns 0 on
// success, 1 on error (message in `err`), 2 when the progress callback asked to stop.
int hr_read(const char* path, int32_t format, const hr_tessellation* tess, const hr_callbacks* cb,
            hr_units* units, char* err, size_t err_len);

// Writes a small test model as STEP (format 0), IGES with OCCT's writer (1: every occurrence a copy) or IGES with
// subfigures (2: parts as 308 definitions, occurrences as 408 instances): kind 0 three boxes, 1 a bolt pattern (one
// bolt shape placed `count` times on a plate), 2 a coloured assembly (part, face and occurrence colours, one hidden
// occurrence), 3 `count` separate box solids, 4 the bolt pattern placed twice as a sub-assembly, 5 a cylinder placed
// upright and upside down. Returns 0 on success, 1 on error (message in `err`).
int hr_write_test(const char* path, int32_t format, int32_t kind, int32_t count, char* err, size_t err_len);

#ifdef __cplusplus
}
#endif
