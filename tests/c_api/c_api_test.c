// SPDX-License-Identifier: BSD-3-Clause
/* tests/c_api/c_api_test.c -- the C API from C99: every error path returns a status and a
 * message, never aborts. Prints "N passed, M failed" and exits non-zero on any failure. */
#define _XOPEN_SOURCE 700
#include <ftw.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "penumbra/penumbra.h"

static int g_passed = 0, g_failed = 0;

static void check(int ok, const char* what, const char* detail) {
  if (ok) {
    ++g_passed;
  } else {
    ++g_failed;
    printf("FAILED: %s%s%s\n", what, detail ? " -- " : "", detail ? detail : "");
  }
}

/* Status `got` equals `want` and the message of `ctx` (NULL: of the thread) contains `needle`.
 * The message is read here, after the call: C leaves argument evaluation order unspecified. */
static void expect(pnb_status got, pnb_status want, pnb_context ctx, const char* needle, const char* what) {
  const char* message = pnb_last_error(ctx);
  char detail[1024];
  snprintf(detail, sizeof detail, "status %d (want %d), message \"%s\" (want \"%s\")", (int)got, (int)want, message,
           needle ? needle : "");
  check(got == want && message != NULL && (needle == NULL || strstr(message, needle) != NULL), what, detail);
}

static int remove_entry(const char* path, const struct stat* sb, int flag, struct FTW* ftw) {
  (void)sb;
  (void)flag;
  (void)ftw;
  return remove(path);
}

/* A 2x1x1 block of unit cubes, 6 tets each (int32 ids, float32 points), plus spare points. */
enum { NX = 2, NP = (NX + 1) * 2 * 2, NT = NX * 6 };
static float g_points[NP * 3];
static int32_t g_tets[NT * 4];
static double g_values[NP];

static void build_mesh(void) {
  int p = 0, t = 0, i, j, k;
  for (k = 0; k < 2; ++k)
    for (j = 0; j < 2; ++j)
      for (i = 0; i <= NX; ++i) {
        g_points[3 * p] = (float)i;
        g_points[3 * p + 1] = (float)j;
        g_points[3 * p + 2] = (float)k;
        g_values[p] = i + 0.5 * j;
        ++p;
      }
  for (i = 0; i < NX; ++i) {
#define ID(a, b, c) ((c) * 2 * (NX + 1) + (b) * (NX + 1) + (a))
    const int32_t v[8] = {ID(i, 0, 0),     ID(i + 1, 0, 0), ID(i + 1, 1, 0), ID(i, 1, 0),
                          ID(i, 0, 1),     ID(i + 1, 0, 1), ID(i + 1, 1, 1), ID(i, 1, 1)};
    const int split[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
    int s, c;
    for (s = 0; s < 6; ++s, ++t)
      for (c = 0; c < 4; ++c) g_tets[4 * t + c] = v[split[s][c]];
#undef ID
  }
}

static pnb_mesh_desc good_mesh(void) {
  static const uint8_t tet_type = PNB_TETRA;
  pnb_mesh_desc m = PNB_MESH_DESC_INIT;
  m.points = g_points;
  m.point_count = NP;
  m.point_type = PNB_FLOAT32;
  m.connectivity = g_tets;
  m.connectivity_count = NT * 4;
  m.offsets = NULL;
  m.index_type = PNB_INT32;
  m.cell_types = &tet_type;
  m.cell_types_count = 1;
  m.topology_version = 1;
  return m;
}

static pnb_field_desc good_field(const char* name) {
  pnb_field_desc f = PNB_FIELD_DESC_INIT;
  f.name = name;
  f.association = PNB_POINT_FIELD;
  f.values = g_values;
  f.count = NP;
  f.components = 1;
  f.stride_bytes = 0;
  f.type = PNB_FLOAT64;
  return f;
}

static void test_create_errors(const char* tmp) {
  pnb_context ctx = (pnb_context)1;
  char config[1024], path[600];
  expect(pnb_create(NULL, &ctx), PNB_INVALID_ARGUMENT, NULL, "config is NULL", "create with NULL config");
  check(ctx == NULL, "create clears *out on failure", NULL);
  expect(pnb_create("{}", NULL), PNB_INVALID_ARGUMENT, NULL, "out is NULL", "create with NULL out");
  expect(pnb_create("{\"output\": {\"directory\": \"x\"}, \"colour\": 1}", &ctx), PNB_INVALID_ARGUMENT,
         NULL, "config: colour is not a known key", "create with unknown key");
  expect(pnb_create("{\"output\": ", &ctx), PNB_INVALID_ARGUMENT, NULL, "not valid JSON",
         "create with broken JSON");
  expect(pnb_create("/nonexistent/config.json", &ctx), PNB_IO_ERROR, NULL, "/nonexistent/config.json",
         "create with missing config file");
  /* A regular file as parent makes the output directory uncreatable, even for root. */
  snprintf(path, sizeof path, "%s/plainfile", tmp);
  fclose(fopen(path, "w"));
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/db\"}, \"cameras\": {\"phi\": [0], \"theta\": [0]}, "
           "\"fields\": [{\"name\": \"T\"}]}", path);
  expect(pnb_create(config, &ctx), PNB_IO_ERROR, NULL, path, "create with unwritable output directory");
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/gpu\"}, \"cameras\": {\"phi\": [0], \"theta\": [0]}, "
           "\"fields\": [{\"name\": \"T\"}], \"backend\": \"gpu\"}", tmp);
  /* No EGL on the node (simulated by naming a library that does not exist): the gpu backend is
   * unavailable, with or without the GPU backend compiled in. */
  setenv("PNB_EGL_LIBRARY", "/nonexistent/libEGL.so.1", 1);
  expect(pnb_create(config, &ctx), PNB_BACKEND_UNAVAILABLE, NULL, "gpu", "create with gpu backend and no EGL");
  unsetenv("PNB_EGL_LIBRARY");
}

static void test_null_context(void) {
  pnb_mesh_desc m = good_mesh();
  pnb_field_desc f = good_field("T");
  expect(pnb_publish_mesh(NULL, &m, PNB_BORROW), PNB_INVALID_ARGUMENT, NULL, "pnb_publish_mesh: ctx is NULL",
         "publish_mesh with NULL ctx");
  expect(pnb_publish_field(NULL, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, NULL, "pnb_publish_field",
         "publish_field with NULL ctx");
  expect(pnb_execute(NULL, 0, 0), PNB_INVALID_ARGUMENT, NULL, "pnb_execute", "execute with NULL ctx");
  expect(pnb_finalize(NULL), PNB_INVALID_ARGUMENT, NULL, "pnb_finalize", "finalize with NULL ctx");
  pnb_destroy(NULL);
  check(1, "destroy(NULL) returns", NULL);
}

/* Publishes `m` and expects failure with `needle` in the message. */
static void bad_mesh(pnb_context ctx, pnb_mesh_desc m, pnb_status want, const char* needle, const char* what) {
  expect(pnb_publish_mesh(ctx, &m, PNB_BORROW), want, ctx, needle, what);
}

static void test_mesh_errors(pnb_context ctx) {
  pnb_mesh_desc m;
  float points[NP * 3];
  int32_t tets[NT * 4];
  uint8_t types[NT];
  int i;
  expect(pnb_publish_mesh(ctx, NULL, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "mesh is NULL", "NULL mesh");
  m = good_mesh();
  expect(pnb_publish_mesh(ctx, &m, (pnb_ownership)7), PNB_INVALID_ARGUMENT, ctx, "own must be",
         "bad ownership");
  m = good_mesh(); m.points = NULL;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "points is NULL", "NULL points");
  m = good_mesh(); m.point_count = 0;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point_count must be > 0", "zero points");
  m = good_mesh(); m.point_count = 0; m.connectivity_count = 0; m.cell_types_count = 0;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "a part without cells is for one rank of a run over several ranks",
           "no cell in one process");
  m = good_mesh(); m.point_count = -5;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point_count must be > 0, got -5", "negative point count");
  m = good_mesh(); m.point_stride_bytes = 8;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point_stride_bytes 8 is smaller than one xyz point (12 bytes)", "small stride");
  m = good_mesh(); m.point_type = PNB_INT32;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point_type must be PNB_FLOAT32 or PNB_FLOAT64", "integer points");
  m = good_mesh(); m.index_type = PNB_FLOAT64;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "index_type must be PNB_INT32 or PNB_INT64", "float ids");
  m = good_mesh(); m.connectivity = NULL;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "connectivity is NULL", "NULL connectivity");
  m = good_mesh(); m.connectivity_count = NT * 4 - 1;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "not a multiple of 4", "connectivity size not a multiple of the cell size");
  m = good_mesh(); m.cell_types = NULL;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "cell_types is NULL", "NULL cell types");
  m = good_mesh(); m.cell_types_count = 0;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "cell_types_count must be >= 1", "no cell types");
  for (i = 0; i < NT; ++i) types[i] = PNB_TETRA;
  m = good_mesh(); m.cell_types = types; m.cell_types_count = NT;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "offsets is NULL but cell_types_count is 12", "mixed types without offsets");
  types[0] = 7;
  m = good_mesh(); m.cell_types = types;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "unsupported cell type 7", "unsupported cell type");

  memcpy(tets, g_tets, sizeof tets);
  tets[4 * 3 + 2] = NP;
  m = good_mesh(); m.connectivity = tets;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "cell 3 references point 12, outside [0, 12)", "index out of range");
  tets[4 * 3 + 2] = -1;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "cell 3 references point -1", "negative index");

  memcpy(points, g_points, sizeof points);
  points[3 * 2 + 1] = NAN;
  m = good_mesh(); m.points = points;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point 2 has a NaN or infinite coordinate", "NaN coordinate");
  points[3 * 2 + 1] = INFINITY;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point 2 has a NaN or infinite coordinate", "infinite coordinate");

  memcpy(tets, g_tets, sizeof tets);
  tets[4 * 5 + 3] = tets[4 * 5 + 2];  /* a repeated vertex flattens the tet */
  m = good_mesh(); m.connectivity = tets;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "cell 5 has zero volume", "zero-volume cell");
  m = good_mesh(); m.struct_size = 0;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "pnb_mesh_desc.struct_size is 0: initialise the struct with PNB_MESH_DESC_INIT",
           "an uninitialised struct_size");
  m = good_mesh(); m.struct_size = 8;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "struct_size is 8, not the size of any version of pnb_mesh_desc", "a struct too small");
  m = good_mesh(); m.struct_size = sizeof m + 8;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "built against a later Penumbra", "a struct from a later version");
  m = good_mesh(); m.point_x = g_points;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "either interleaved (points) or as three arrays", "points given twice");
  m = good_mesh(); m.points = NULL; m.point_x = g_points; m.point_y = g_points + 1;
  bad_mesh(ctx, m, PNB_INVALID_ARGUMENT, "point_x, point_y and point_z go together", "a missing coordinate array");
}

static void test_field_errors(pnb_context ctx) {
  pnb_field_desc f;
  expect(pnb_publish_field(ctx, NULL, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "field is NULL", "NULL field");
  f = good_field(NULL);
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "name is NULL", "NULL name");
  f = good_field("T"); f.struct_size = 0;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "pnb_field_desc.struct_size is 0",
         "an uninitialised field struct_size");
  f = good_field("T"); f.count = NP - 1;
  expect(pnb_publish_field(ctx, &f, PNB_COPY), PNB_INVALID_ARGUMENT, ctx,
         "field 'T' has 11 values but the mesh has 12 points", "wrong value count");
  f = good_field("T"); f.association = PNB_CELL_FIELD; f.count = 5;
  expect(pnb_publish_field(ctx, &f, PNB_COPY), PNB_INVALID_ARGUMENT, ctx, "has 5 values but the mesh has 12 cells",
         "point-sized cell field");
  f = good_field("T"); f.association = (pnb_association)5;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "association must be",
         "bad association");
  f = good_field("T"); f.values = NULL;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "values pointer is null",
         "NULL values");
  f = good_field("T"); f.components = 0;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "components must be >= 1",
         "zero components");
  f = good_field("T"); f.type = PNB_INT32;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "type must be PNB_FLOAT32",
         "integer field");
  f = good_field("T"); f.stride_bytes = 4;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx,
         "stride_bytes 4 is smaller than one item (8 bytes)", "small field stride");
  f = good_field("T"); f.count = -1;
  expect(pnb_publish_field(ctx, &f, PNB_BORROW), PNB_INVALID_ARGUMENT, ctx, "count must be >= 0",
         "negative count");
  /* Fields the config does not render are ignored, even with no values at all. */
  f = good_field("unused"); f.values = NULL; f.count = 3;
  expect(pnb_publish_field(ctx, &f, PNB_COPY), PNB_OK, ctx, NULL, "unconfigured field ignored");
}

/* pnb_step_needs: asked before every step of a run whose trigger has both rules and whose store
 * keeps every other cycle, its answers are what pnb_execute then does, and asking changes nothing. */
static void test_step_needs(const char* tmp) {
  char config[1024];
  pnb_context ctx = NULL;
  pnb_mesh_desc mesh = good_mesh();
  pnb_field_desc field = good_field("T");
  pnb_needs needs = PNB_NEEDS_INIT;
  pnb_step_stats stats = PNB_STEP_STATS_INIT;
  int cycle, agreed = 1, rendered = 0, stored = 0;
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/needs-db\"}, \"image\": {\"width\": 8, \"height\": 8},"
           " \"cameras\": {\"phi\": [0], \"theta\": [30]}, \"fields\": [{\"name\": \"T\"},"
           " {\"name\": \"T\", \"component\": 0}, {\"name\": \"P\"}],"
           " \"trigger\": {\"every_cycles\": 4, \"every_time\": 0.25},"
           " \"store\": {\"directory\": \"%s/needs-store\", \"every_cycles\": 2}}", tmp, tmp);
  expect(pnb_create(config, &ctx), PNB_OK, NULL, NULL, "create for step needs");
  if (!ctx) return;
  expect(pnb_step_needs(ctx, 0.0, 0, &needs), PNB_OK, ctx, NULL, "step needs before the mesh");
  check(needs.needs_mesh == 1 && needs.renders == 1 && needs.stores == 1, "before the mesh: the mesh, a render, a record", NULL);
  check(needs.field_count == 2 && strcmp(pnb_needed_field(ctx, 0), "T") == 0 && strcmp(pnb_needed_field(ctx, 1), "P") == 0,
        "the fields named once each, in the config's order", NULL);
  check(pnb_needed_field(ctx, 2) == NULL && pnb_needed_field(ctx, -1) == NULL && pnb_needed_field(NULL, 0) == NULL,
        "a needed field out of range is NULL", NULL);
  expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish for step needs");
  for (cycle = 0; cycle < 12; ++cycle) {
    const double time = 0.1 * cycle;
    pnb_needs again = PNB_NEEDS_INIT;
    expect(pnb_step_needs(ctx, time, cycle, &needs), PNB_OK, ctx, NULL, "step needs");
    expect(pnb_step_needs(ctx, time, cycle, &again), PNB_OK, ctx, NULL, "step needs asked again");
    agreed &= memcmp(&needs, &again, sizeof needs) == 0 && needs.needs_mesh == 0;
    agreed &= needs.field_count == ((needs.renders || needs.stores) ? 2 : 0);
    pnb_publish_field(ctx, &field, PNB_BORROW);
    field.name = "P";
    pnb_publish_field(ctx, &field, PNB_BORROW);
    field.name = "T";
    stats.cycle = -1;
    expect(pnb_execute(ctx, time, cycle), PNB_OK, ctx, NULL, "execute after step needs");
    pnb_last_step(ctx, &stats);
    agreed &= (stats.cycle == cycle) == (needs.renders == 1);
    rendered += needs.renders;
    stored += needs.stores;
  }
  check(agreed, "every answer is what pnb_execute then did, and asking twice changes nothing", NULL);
  /* Renders: cycles 0, 4, 8 by cycle and 0, 3, 5, 8, 10 by time (0.25, 0.5, 0.75, 1.0 first reached). */
  check(rendered == 6 && stored == 6, "six steps render and six are stored", NULL);
  needs.struct_size = 0;
  expect(pnb_step_needs(ctx, 1.2, 12, &needs), PNB_INVALID_ARGUMENT, ctx, "pnb_needs.struct_size is 0",
         "step needs into an uninitialised struct");
  expect(pnb_step_needs(ctx, 1.2, 12, NULL), PNB_INVALID_ARGUMENT, ctx, "out is NULL", "step needs into NULL");
  expect(pnb_step_needs(NULL, 1.2, 12, &needs), PNB_INVALID_ARGUMENT, NULL, "pnb_step_needs", "step needs of a NULL ctx");
  pnb_destroy(ctx);
}

/* "budget": a step that cannot keep to its budget says what it gave up. */
static void test_budget(const char* tmp) {
  char config[1024];
  pnb_context ctx = NULL;
  pnb_mesh_desc mesh = good_mesh();
  pnb_field_desc field = good_field("T");
  pnb_step_stats stats = PNB_STEP_STATS_INIT;
  int cycle;
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/budget-db\"}, \"image\": {\"width\": 16, \"height\": 16},"
           " \"cameras\": {\"phi\": [0, 90], \"theta\": [30]}, \"fields\": [{\"name\": \"T\"}],"
           " \"budget\": {\"ms\": 0.0001}}", tmp);
  expect(pnb_create(config, &ctx), PNB_OK, NULL, NULL, "create with a budget");
  if (!ctx) return;
  expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish mesh, budget");
  pnb_publish_field(ctx, &field, PNB_BORROW);
  expect(pnb_execute(ctx, 0, 0), PNB_OK, ctx, NULL, "execute, budget, first step");
  expect(pnb_last_step(ctx, &stats), PNB_OK, ctx, NULL, "last step, budget, first step");
  check(stats.degraded == 0 && stats.cameras_rendered == 2 && stats.image_scale == 1,
        "budget: the first step measures, giving up nothing", NULL);
  for (cycle = 1; cycle < 3; ++cycle) {
    pnb_publish_field(ctx, &field, PNB_BORROW);
    expect(pnb_execute(ctx, cycle, cycle), PNB_OK, ctx, NULL, "execute, budget");
  }
  expect(pnb_last_step(ctx, &stats), PNB_OK, ctx, NULL, "last step, budget");
  check(stats.budget_ms == 0.0001 && stats.degraded == (PNB_DEGRADED_IMAGE | PNB_DEGRADED_CAMERAS) &&
            stats.image_scale == 0.25 && stats.cameras_rendered == 1 && stats.level0_resolution == 0 && stats.images == 1 &&
            stats.status == PNB_OK,
        "budget: an unlit step gives up image size, then cameras", NULL);
  pnb_destroy(ctx);
}

/* "async": the steps handed to a worker; pnb_finalize drains it and every step is in the database. */
static void test_async(const char* tmp) {
  char config[1024], csv[700];
  pnb_context ctx = NULL;
  pnb_mesh_desc mesh = good_mesh();
  pnb_field_desc field = good_field("T");
  pnb_step_stats stats = PNB_STEP_STATS_INIT;
  FILE* f;
  int cycle, lines = 0, c;
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/async-db\"}, \"image\": {\"width\": 8, \"height\": 8},"
           " \"cameras\": {\"phi\": [0], \"theta\": [30]}, \"fields\": [{\"name\": \"T\"}],"
           " \"async\": {\"backpressure\": \"wait\"}}", tmp);
  expect(pnb_create(config, &ctx), PNB_OK, NULL, NULL, "create async");
  if (!ctx) return;
  expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish mesh, async");
  for (cycle = 0; cycle < 4; ++cycle) {
    pnb_publish_field(ctx, &field, PNB_BORROW);
    expect(pnb_execute(ctx, cycle, cycle), PNB_OK, ctx, NULL, "execute, async");
  }
  expect(pnb_finalize(ctx), PNB_OK, ctx, NULL, "finalize drains the worker");
  expect(pnb_last_step(ctx, &stats), PNB_OK, ctx, NULL, "last step, async");
  check(stats.cycle == 3 && stats.skipped_steps == 0, "async: the last step is the last one handed over, none skipped", NULL);
  pnb_destroy(ctx);
  snprintf(csv, sizeof csv, "%s/async-db/data.csv", tmp);
  f = fopen(csv, "r");
  if (f) {
    while ((c = fgetc(f)) != EOF) lines += c == '\n';
    fclose(f);
  }
  check(lines == 1 + 4, "async: data.csv lists every step", NULL);
}

int main(void) {
  char tmp[] = "/tmp/pnb-c-api-XXXXXX";
  char config[1024], csv[700];
  pnb_context ctx = NULL;
  pnb_mesh_desc mesh;
  pnb_field_desc field;
  FILE* f;
  if (!mkdtemp(tmp)) return 2;
  build_mesh();
  check(pnb_version() != NULL && strlen(pnb_version()) > 0, "pnb_version", NULL);
  check(pnb_last_error(NULL) != NULL, "pnb_last_error(NULL) is never NULL", NULL);
  test_create_errors(tmp);
  test_null_context();
  test_step_needs(tmp);
  test_async(tmp);
  test_budget(tmp);

  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s/db\"}, \"image\": {\"width\": 16, \"height\": 16},"
           " \"cameras\": {\"phi\": [0, 90], \"theta\": [30]}, \"fields\": [{\"name\": \"T\"}]}", tmp);
  expect(pnb_create(config, &ctx), PNB_OK, NULL, NULL, "create");
  if (!ctx) {
    printf("%d passed, %d failed\n", g_passed, g_failed + 1);
    return 1;
  }
  check(strcmp(pnb_last_error(ctx), "") == 0, "no error message on a fresh context", pnb_last_error(ctx));
  expect(pnb_execute(ctx, 0.0, 0), PNB_INVALID_OPERATION, ctx, "no mesh published", "execute before mesh");
  field = good_field("T");
  expect(pnb_publish_field(ctx, &field, PNB_BORROW), PNB_INVALID_OPERATION, ctx,
         "call pnb_publish_mesh first", "field before mesh");
  test_mesh_errors(ctx);

  {
    /* Explicit offsets and one type per cell (as a mixed-cell mesh would give them). */
    int32_t offsets[NT + 1];
    uint8_t types[NT];
    int i;
    for (i = 0; i <= NT; ++i) offsets[i] = 4 * i;
    for (i = 0; i < NT; ++i) types[i] = PNB_TETRA;
    mesh = good_mesh();
    mesh.offsets = offsets;
    mesh.cell_types = types;
    mesh.cell_types_count = NT;
    mesh.topology_version = 5;
    expect(pnb_publish_mesh(ctx, &mesh, PNB_COPY), PNB_OK, ctx, NULL, "publish mesh with offsets and per-cell types");
    offsets[3] = 99;
    mesh.topology_version = 6;
    expect(pnb_publish_mesh(ctx, &mesh, PNB_COPY), PNB_INVALID_ARGUMENT, ctx, "cell 2 has offsets [8, 99)",
           "offsets past the connectivity");
  }
  {
    /* The same points as three strided arrays (x, y, z of the interleaved float32 array). */
    mesh = good_mesh();
    mesh.points = NULL;
    mesh.point_x = g_points;
    mesh.point_y = g_points + 1;
    mesh.point_z = g_points + 2;
    mesh.point_axis_stride_bytes = 3 * sizeof(float);
    mesh.topology_version = 7;
    expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish three coordinate arrays");
    /* A caller built against ABI 2 passes the smaller struct: the arrays take their defaults. */
    mesh = good_mesh();
    mesh.struct_size = (uint32_t)offsetof(pnb_mesh_desc, point_x);
    mesh.point_x = g_points; /* beyond the caller's struct: never read */
    mesh.topology_version = 8;
    expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish an ABI-2 sized struct");
  }
  mesh = good_mesh();
  expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "publish valid mesh");
  expect(pnb_publish_mesh(ctx, &mesh, PNB_BORROW), PNB_OK, ctx, NULL, "republish same topology");
  test_field_errors(ctx);

  field = good_field("T");
  expect(pnb_publish_field(ctx, &field, PNB_BORROW), PNB_OK, ctx, NULL, "publish field");
  expect(pnb_execute(ctx, 0.0, 0), PNB_OK, ctx, NULL, "execute step 0");
  expect(pnb_execute(ctx, 0.1, 1), PNB_INVALID_OPERATION, ctx, "field 'T' was not published for cycle 1",
         "execute without the field");
  expect(pnb_execute(ctx, NAN, 2), PNB_INVALID_ARGUMENT, ctx, "time must be finite", "NaN time");
  expect(pnb_publish_field(ctx, &field, PNB_COPY), PNB_OK, ctx, NULL, "publish copied field");
  expect(pnb_execute(ctx, 0.2, 2), PNB_OK, ctx, NULL, "a later step still works");
  {
    pnb_step_stats stats;
    memset(&stats, 0xff, sizeof stats);
    stats.struct_size = 0;
    expect(pnb_last_step(ctx, &stats), PNB_INVALID_ARGUMENT, ctx, "pnb_step_stats.struct_size is 0",
           "last step into an uninitialised struct");
    stats.struct_size = sizeof stats;
    expect(pnb_last_step(ctx, &stats), PNB_OK, ctx, NULL, "last step");
    check(stats.struct_size == sizeof stats, "last step keeps the caller's struct_size", NULL);
    check(stats.cycle == 2 && stats.images == 2, "last step: cycle 2, two cameras", NULL);
    check(stats.total_ms >= stats.render_ms && stats.render_ms > 0, "last step: times", NULL);
    check(stats.light_ms == 0 && stats.light_residual == 0, "last step: no light volume, no light figures", NULL);
    {
      const double stages = stats.store_ms + stats.gather_ms + stats.light_ms + stats.render_ms + stats.composite_ms +
                            stats.write_ms + stats.other_ms;
      check(stats.gather_ms >= 0 && stats.composite_ms > 0 && stats.write_ms > 0 && stats.other_ms >= 0,
            "last step: every stage timed", NULL);
      check(fabs(stages - stats.total_ms) <= 1e-6 * (1 + stats.total_ms), "last step: the stages add up to total_ms", NULL);
    }
    /* A caller built against ABI 4 passes the smaller struct: the stages are not written. */
    memset(&stats, 0, sizeof stats);
    stats.struct_size = (uint32_t)offsetof(pnb_step_stats, store_ms);
    stats.write_ms = -1;
    expect(pnb_last_step(ctx, &stats), PNB_OK, ctx, NULL, "last step into an ABI-4 sized struct");
    check(stats.cycle == 2 && stats.write_ms == -1, "an ABI-4 struct gets what it holds and nothing beyond", NULL);
    expect(pnb_last_step(ctx, NULL), PNB_INVALID_ARGUMENT, ctx, "out is NULL", "last step into NULL");
    expect(pnb_last_step(NULL, &stats), PNB_INVALID_ARGUMENT, NULL, "pnb_last_step", "last step of a NULL ctx");
  }

  snprintf(csv, sizeof csv, "%s/db/data.csv", tmp);
  f = fopen(csv, "r");
  check(f != NULL, "data.csv written", csv);
  if (f) {
    int lines = 0, c;
    while ((c = fgetc(f)) != EOF) lines += c == '\n';
    fclose(f);
    check(lines == 1 + 2 * 2, "data.csv lists 2 steps x 2 cameras", NULL);
  }

  expect(pnb_finalize(ctx), PNB_OK, ctx, NULL, "finalize");
  expect(pnb_execute(ctx, 0.3, 3), PNB_INVALID_OPERATION, ctx, "finalized", "execute after finalize");
  pnb_destroy(ctx);

  /* The same directory again: refused by default. */
  expect(pnb_create(config, &ctx), PNB_INVALID_ARGUMENT, NULL, "exists and is not empty",
         "existing database refused");

  nftw(tmp, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
  printf("%d passed, %d failed\n", g_passed, g_failed);
  return g_failed == 0 ? 0 : 1;
}
