// SPDX-License-Identifier: BSD-3-Clause
/* insitu/include/penumbra/penumbra.h -- Penumbra's C API for simulation codes (C99, Fortran via bind(C)).
 *
 * Typical time loop:
 *   pnb_context ctx;  pnb_create("config.json", &ctx);        // path or JSON text
 *   pnb_publish_mesh(ctx, &mesh, PNB_BORROW);                   // once, or when topology changes
 *   for (step...) { pnb_publish_field(ctx, &field, PNB_BORROW); pnb_execute(ctx, time, step); }
 *   pnb_destroy(ctx);                                           // flushes and finalizes
 *
 * Every call returns a status; on failure pnb_last_error(ctx) describes it. No call ever aborts
 * the host program or lets an exception escape. A context is not thread-safe: call it from one
 * thread at a time. Borrowed arrays (PNB_BORROW) must stay valid and unchanged until the next
 * pnb_execute returns; Penumbra copies what it keeps.
 *
 * The structs passed in and out start with `struct_size`, the size of the struct as the caller
 * was compiled: initialise them with PNB_MESH_DESC_INIT, PNB_FIELD_DESC_INIT and
 * PNB_STEP_STATS_INIT (the Fortran types carry it as their default). Later versions add members
 * at the end only, after the previous version's size; the library reads a caller's older, smaller struct with the added members at
 * their defaults, so a binary built against this header keeps working with later libraries.
 * Versions of the library, this ABI and the file formats: docs/versions.md. */
#ifndef PENUMBRA_PENUMBRA_H
#define PENUMBRA_PENUMBRA_H

#include <stdint.h>

#include "penumbra/core/export.h"

PNB_PUBLIC_BEGIN

#ifdef __cplusplus
extern "C" {
#endif

/* The C ABI's version: bumped when a struct grows or a call is added. */
#define PNB_ABI_VERSION 5

typedef struct pnb_context_s* pnb_context;

typedef enum {
  PNB_OK = 0,
  PNB_INVALID_ARGUMENT = 1,
  PNB_INVALID_OPERATION = 2,
  PNB_OUT_OF_MEMORY = 3,
  PNB_BACKEND_UNAVAILABLE = 4,
  PNB_INTERNAL_ERROR = 5,
  PNB_IO_ERROR = 6
} pnb_status;

typedef enum { PNB_BORROW = 0, PNB_COPY = 1 } pnb_ownership;

typedef enum { PNB_FLOAT32 = 0, PNB_FLOAT64 = 1, PNB_INT32 = 2, PNB_INT64 = 3 } pnb_type;

/* VTK cell type ids. */
enum { PNB_TETRA = 10, PNB_HEXAHEDRON = 12, PNB_WEDGE = 13, PNB_PYRAMID = 14 };

typedef enum { PNB_POINT_FIELD = 0, PNB_CELL_FIELD = 1 } pnb_association;

/* An unstructured mesh as views of the caller's arrays (VTK ordering).
 * points: point_count items of xyz in point_type (PNB_FLOAT32/64), point_stride_bytes apart
 *         (0 means packed); or NULL with point_x, point_y, point_z (below). connectivity: connectivity_count ids in index_type (PNB_INT32/64).
 * offsets: cell_count + 1 entries in index_type, or NULL when every cell has the same type.
 * cell_types: one uint8 VTK id per cell, or a single entry when cell_types_count == 1.
 * topology_version: bump when the connectivity changes (cells, their points, the point count);
 *                   points may move under an unchanged version (Lagrangian and ALE codes: see
 *                   pnb_publish_mesh).
 * Over MPI ranks (penumbra_mpi.h), a rank with no cell gives point_count, connectivity_count and
 * cell_types_count 0 (the arrays may then be NULL); in one process a mesh has points and cells. */
typedef struct {
  uint32_t struct_size; /* sizeof(pnb_mesh_desc) as the caller was compiled (PNB_MESH_DESC_INIT) */
  const void* points;
  int64_t point_count;
  int64_t point_stride_bytes;
  pnb_type point_type;
  const void* connectivity;
  int64_t connectivity_count;
  const void* offsets;
  pnb_type index_type;
  const uint8_t* cell_types;
  int64_t cell_types_count;
  uint64_t topology_version;
  /* ABI 3: the coordinates as three arrays instead (points NULL), each in point_type, items
   * point_axis_stride_bytes apart (0 means packed): a solver's x[], y[], z[] without a copy. */
  const void* point_x;
  const void* point_y;
  const void* point_z;
  int64_t point_axis_stride_bytes;
  /* ABI 4: VTK's vtkGhostType per cell (uint8), or NULL. Cells with the duplicate-cell bit (1) are
   * another rank's copies (a halo): their points' cell-field averages include them, but they are
   * never rendered, lit or stored twice. */
  const uint8_t* cell_ghosts;
} pnb_mesh_desc;

/* Every member at its default: no arrays, float64 points, int64 indices. */
#define PNB_MESH_DESC_INIT {sizeof(pnb_mesh_desc), 0, 0, 0, PNB_FLOAT64, 0, 0, 0, PNB_INT64, 0, 0, 0, 0, 0, 0, 0, 0}

/* One field: count items of `components` values each, in type (PNB_FLOAT32/64), stride_bytes
 * apart (0 means packed). */
typedef struct {
  uint32_t struct_size; /* sizeof(pnb_field_desc) as the caller was compiled (PNB_FIELD_DESC_INIT) */
  const char* name;
  pnb_association association;
  const void* values;
  int64_t count;
  int components;
  int64_t stride_bytes;
  pnb_type type;
} pnb_field_desc;

/* Every member at its default: a packed point field of one float64 component, no values yet. */
#define PNB_FIELD_DESC_INIT {sizeof(pnb_field_desc), 0, PNB_POINT_FIELD, 0, 0, 1, 0, PNB_FLOAT64}

/* Creates a context from a JSON config: a file path, or JSON text starting with '{' (schema in
 * insitu/README.md). Opens the output database at once: PNB_INVALID_ARGUMENT for a bad config
 * or a non-empty output directory without "if_exists": "resume", PNB_IO_ERROR (naming the path)
 * when the directory cannot be created or written, PNB_BACKEND_UNAVAILABLE for a backend this
 * build lacks. On failure *out is NULL and pnb_last_error(NULL) tells why. */
pnb_status pnb_create(const char* config, pnb_context* out);
/* Checks a config as pnb_create does (a file path, or JSON text starting with '{'), without
 * creating anything: no context, database, store or directory, no GPU opened, nothing written.
 * Returns PNB_OK or the status pnb_create gives for the same config: PNB_INVALID_ARGUMENT for a
 * bad config (the message names the key path), PNB_IO_ERROR for a config file that cannot be
 * read, PNB_BACKEND_UNAVAILABLE for keys that no backend of the config can run together; on
 * failure pnb_last_error(NULL) tells why. What depends on the machine is left to pnb_create:
 * the output and store directories (non-empty without "resume", not writable, a resumed
 * data.csv's header) and whether a GPU can be opened. */
pnb_status pnb_check_config(const char* config);
/* Publishes (or republishes) the mesh: PNB_INVALID_ARGUMENT for a struct_size that is not of any
 * version's pnb_mesh_desc (0: not initialised with PNB_MESH_DESC_INIT; larger than this
 * library's: built against a later version). Validates it (errors name the offending cell or point)
 * and prepares it for rendering. Penumbra copies what it keeps, so the arrays may be freed after
 * the call whatever `own` says. Republishing the same topology_version compares the points with
 * the prepared ones (one pass, about a millisecond per million points): unchanged, nothing more
 * is done; moved, only what depends on the positions is redone (the ray caster's geometry, the
 * light volume's grid and walks, from the light before the motion as a warm start; the split into
 * tets and the adjacency are kept), a small part of a preparation, and the store records the
 * coordinates in the same segment. Motion that inverts or flattens a cell is refused with
 * PNB_INVALID_ARGUMENT naming the cell (the mesh before the motion stays prepared); points that
 * were duplicates of each other and move apart make a new preparation. */
pnb_status pnb_publish_mesh(pnb_context ctx, const pnb_mesh_desc* mesh, pnb_ownership own);
/* Publishes one field for the next execute (struct_size checked as for the mesh). Fields the config does not render are ignored
 * (not read, not copied). PNB_BORROW fields are read during the next pnb_execute and then
 * forgotten; PNB_COPY fields are copied now and kept until republished or the topology changes.
 * PNB_INVALID_OPERATION before the first mesh. */
pnb_status pnb_publish_field(pnb_context ctx, const pnb_field_desc* field, pnb_ownership own);
/* Runs the per-step pipeline for simulation time `time` and step `cycle`: renders if the
 * config's trigger fires and appends the images to the Cinema database. A failed step is
 * recorded and skipped; later steps still run. A configured field that was not published for a
 * rendering step gives PNB_INVALID_OPERATION naming it (the other fields are still written);
 * so does a call before any mesh was published. With "async" in the config, a step that renders
 * or stores copies the fields it reads and returns while a worker thread renders it; its failure
 * is the status of the next pnb_execute or of pnb_finalize, naming its cycle. */
pnb_status pnb_execute(pnb_context ctx, double time, int64_t cycle);
/* What the last rendering step did (zeros before the first). light_*: the light volume's
 * solve of the last rendered field (lighting model "light-volume"; 0 otherwise): its time, its
 * remaining change (0 once converged) and whether it converged within the step's budget. */
typedef struct {
  uint32_t struct_size; /* sizeof(pnb_step_stats) as the caller was compiled (PNB_STEP_STATS_INIT) */
  int64_t cycle;
  int images;
  double render_ms;
  double total_ms;
  double light_ms;
  double light_residual;
  int light_converged;
  /* ABI 5: the other stages, so that store + gather + light + render + composite + write + other
   * = total_ms: the step's fields recorded in the store (on a step that stores), the fields
   * gathered, converted and normalised, the views composited (over ranks: their runs exchanged
   * and merged), the PNGs encoded and written and data.csv committed, and what is left. */
  double store_ms;
  double gather_ms;
  double composite_ms;
  double write_ms;
  double other_ms;
  /* ABI 5: with "async" and "backpressure": "skip", the steps skipped so far because the worker
   * was still busy (never in the database or the store). */
  int64_t skipped_steps;
  /* ABI 5: with "budget", the step's budget (0: none) and what the step gave up to keep to it:
   * degraded holds the PNB_DEGRADED_* bits taken, image_scale the fraction of the configured width
   * and height the images were rendered at (then enlarged to it), cameras_rendered how many of
   * the configured cameras rendered, level0_resolution the light volume's coarsened level 0
   * (0: as configured). status is the step's own outcome: PNB_OK, or the error its pnb_execute
   * returned (with "async", the error the next pnb_execute or pnb_finalize returns, naming the
   * step's cycle; over MPI ranks the same on every rank). */
  double budget_ms;
  double image_scale;
  int degraded;
  int cameras_rendered;
  int level0_resolution;
  pnb_status status;
} pnb_step_stats;
#define PNB_STEP_STATS_INIT {sizeof(pnb_step_stats), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, PNB_OK}
/* pnb_step_stats.degraded, in the order a step over its budget gives them up. */
#define PNB_DEGRADED_LIGHT 1   /* the light volume stopped short: it converges over the next steps */
#define PNB_DEGRADED_LEVEL0 2  /* the light volume's level 0 coarsened */
#define PNB_DEGRADED_IMAGE 4   /* images rendered smaller, then enlarged */
#define PNB_DEGRADED_CAMERAS 8 /* some cameras left for the next steps */
/* Fills the members of *out that its struct_size holds; PNB_INVALID_ARGUMENT for a NULL out or
 * a struct_size that is not of any version's struct. */
pnb_status pnb_last_step(pnb_context ctx, pnb_step_stats* out);
/* What pnb_execute(ctx, time, cycle) will need, asked before the solver builds anything (ABI 5):
 * renders (the trigger fires), stores (the store records this cycle), needs_mesh (no mesh is
 * published yet: pnb_execute fails without one; a mesh whose points moved must be republished
 * whatever this says) and field_count, the fields pnb_execute will read (the rendered ones when
 * the step renders or stores, and at every step those a trigger "when" watches), named by
 * pnb_needed_field. Decided exactly as pnb_execute decides, and
 * records nothing: asking twice, or not at all, changes no later step. Over MPI ranks it asks
 * this rank alone (no communication); ranks that pass the same time and cycle, as pnb_execute
 * requires, get the same answer. */
typedef struct {
  uint32_t struct_size; /* sizeof(pnb_needs) as the caller was compiled (PNB_NEEDS_INIT) */
  int renders;
  int stores;
  int needs_mesh;
  int field_count;
} pnb_needs;
#define PNB_NEEDS_INIT {sizeof(pnb_needs), 0, 0, 0, 0}
pnb_status pnb_step_needs(pnb_context ctx, double time, int64_t cycle, pnb_needs* out);
/* Name of needed field `index` (0 .. field_count - 1) of the last pnb_step_needs on ctx; NULL for
 * an index out of range. Valid until the next pnb_step_needs on ctx. */
const char* pnb_needed_field(pnb_context ctx, int index);
/* Finalizes: flushes pending work; the context stays valid only for pnb_destroy. */
pnb_status pnb_finalize(pnb_context ctx);
/* Message of the last failed call on ctx (or of the last failed pnb_create when ctx is NULL);
 * valid until the next call on ctx. Never NULL. */
const char* pnb_last_error(pnb_context ctx);
/* Finalizes if needed and frees ctx; accepts NULL. */
void pnb_destroy(pnb_context ctx);
/* Library version string, e.g. "0.1.0". */
const char* pnb_version(void);

#ifdef __cplusplus
}
#endif

PNB_PUBLIC_END

#endif /* PENUMBRA_PENUMBRA_H */
