// SPDX-License-Identifier: BSD-3-Clause
/* examples/lagrangian_vortex/main.c -- a Lagrangian "solver" whose mesh moves every step.
 *
 * A slab of hexahedra is carried by a prescribed vortex about its vertical axis: a material point
 * that starts at distance r from the axis turns by A sin(2 pi t / P) exp(-r^2 / R^2), so the mesh
 * winds up, is sheared hardest half a period in, and unwinds. As in a Lagrangian hydrodynamics
 * code the connectivity never changes and the coordinates live in three arrays x[], y[], z[],
 * which Penumbra reads in place: every step republishes them under the same topology_version, and
 * only what depends on the positions is redone. The temperature a material point carries and the
 * flow speed are rendered every 8 cycles; every cycle is kept in a compressed history (one store
 * segment: the connectivity once, the coordinates and fields per step) that penumbra-replay renders
 * again with another config.
 * Usage: penumbra-example-lagrangian [--async] [OUTPUT_DIR [STORE_DIR]]
 *        (defaults ./penumbra-example-lagrangian-db and OUTPUT_DIR-history); with --async the
 *        steps render on Penumbra's worker thread while the vortex goes on, into the same files. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "penumbra/penumbra.h"

enum { NX = 40, NY = 40, NZ = 6, CYCLES = 96 };
#define NPTS ((NX + 1) * (NY + 1) * (NZ + 1))
#define NCELLS (NX * NY * NZ)

static const double kPi = 3.14159265358979323846;
static const double kTurn = 1.3;    /* A: the largest turn, at the axis (radians) */
static const double kRadius = 0.3;  /* R: how far from the axis the vortex reaches */
static const double kPeriod = 1.0;  /* P: wound up and back in one period */

static int64_t node(int i, int j, int k) { return ((int64_t)k * (NY + 1) + j) * (NX + 1) + i; }

static int check(pnb_context ctx, pnb_status s, const char* what) {
  if (s == PNB_OK) return 1;
  fprintf(stderr, "penumbra-example-lagrangian: %s failed: %s\n", what, pnb_last_error(ctx));
  return 0;
}

/* The points at time t, from where they started (x0, y0): the vortex turns each about (0.5, 0.5).
 * Also the flow speed there. */
static void move_points(double t, const double* x0, const double* y0, double* x, double* y, double* speed) {
  int p;
  const double turn = kTurn * sin(2 * kPi * t / kPeriod), rate = kTurn * 2 * kPi / kPeriod * cos(2 * kPi * t / kPeriod);
  for (p = 0; p < NPTS; ++p) {
    const double dx = x0[p] - 0.5, dy = y0[p] - 0.5, r2 = dx * dx + dy * dy;
    const double falloff = exp(-r2 / (kRadius * kRadius)), a = turn * falloff;
    x[p] = 0.5 + cos(a) * dx - sin(a) * dy;
    y[p] = 0.5 + sin(a) * dx + cos(a) * dy;
    speed[p] = fabs(rate * falloff) * sqrt(r2);
  }
}

static void make_cells(int64_t* hexes) {
  int i, j, k, c = 0;
  for (k = 0; k < NZ; ++k)
    for (j = 0; j < NY; ++j)
      for (i = 0; i < NX; ++i, ++c) {
        /* VTK hexahedron order: bottom quad counter-clockwise, then the top quad. */
        const int64_t v[8] = {node(i, j, k),     node(i + 1, j, k),     node(i + 1, j + 1, k),     node(i, j + 1, k),
                              node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        memcpy(&hexes[8 * c], v, sizeof v);
      }
}

static pnb_context create(const char* out, const char* store, int async) {
  char config[2048];
  pnb_context ctx = NULL;
  /* Fixed ranges: one colour scale for the whole run (the flow stops everywhere when the vortex
   * turns back, where an automatic range would stretch a field of nearly zeros). */
  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s\"},"
           " \"image\": {\"width\": 128, \"height\": 128, \"background\": [0.08, 0.08, 0.1]},"
           " \"cameras\": {\"phi\": [-60, 30], \"theta\": [55], \"fov\": 30},"
           " \"fields\": ["
           "   {\"name\": \"temperature\", \"range\": [0, 1], \"transfer_function\": {"
           "      \"colors\": [[0, 0.1, 0.2, 0.5], [0.5, 0.9, 0.4, 0.1], [1, 1, 1, 0.7]],"
           "      \"opacities\": [[0, 0.5], [0.2, 2], [1, 14]]}},"
           "   {\"name\": \"speed\", \"range\": [0, 1.1], \"transfer_function\": {"
           "      \"colors\": [[0, 0.1, 0.3, 0.6], [1, 1, 0.9, 0.3]], \"opacities\": [[0, 0.3], [1, 6]]}}],"
           " \"trigger\": {\"every_cycles\": 8},"
           " \"store\": {\"directory\": \"%s\", \"window\": 16, \"error_bound\": {\"relative\": 0.001}}%s}",
           out, store, async ? ", \"async\": true" : "");
  if (!check(NULL, pnb_create(config, &ctx), "pnb_create")) return NULL;
  return ctx;
}

int main(int argc, char** argv) {
  const char* positional[2] = {NULL, NULL};
  const char* out;
  char store[1024];
  static double x0[NPTS], y0[NPTS], x[NPTS], y[NPTS], z[NPTS], temperature0[NPTS], temperature[NPTS], speed[NPTS];
  static int64_t hexes[NCELLS * 8];
  static const uint8_t hex_type = PNB_HEXAHEDRON;
  pnb_mesh_desc mesh = PNB_MESH_DESC_INIT;
  pnb_context ctx;
  int i, j, k, cycle, failures = 0, async = 0, given = 0;

  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--async") == 0)
      async = 1;
    else if (given < 2)
      positional[given++] = argv[i];
  }
  out = positional[0] ? positional[0] : "penumbra-example-lagrangian-db";
  if (positional[1])
    snprintf(store, sizeof store, "%s", positional[1]);
  else
    snprintf(store, sizeof store, "%s-history", out);
  for (k = 0; k <= NZ; ++k)
    for (j = 0; j <= NY; ++j)
      for (i = 0; i <= NX; ++i) {
        const int64_t p = node(i, j, k);
        x0[p] = (double)i / NX;
        y0[p] = (double)j / NY;
        z[p] = 0.2 * k / NZ;
        /* A warm streak across the vortex, carried by the material. */
        temperature0[p] = exp(-pow((y0[p] - 0.5) / 0.08, 2)) * (0.6 + 0.4 * x0[p]) + 0.15 * k / NZ;
      }
  make_cells(hexes);
  ctx = create(out, store, async);
  if (!ctx) return 1;

  mesh.points = NULL; /* the coordinates as three arrays, read in place */
  mesh.point_x = x;
  mesh.point_y = y;
  mesh.point_z = z;
  mesh.point_count = NPTS;
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = hexes;
  mesh.connectivity_count = NCELLS * 8;
  mesh.index_type = PNB_INT64;
  mesh.cell_types = &hex_type;
  mesh.cell_types_count = 1;
  mesh.topology_version = 1; /* the connectivity never changes */

  for (cycle = 0; cycle < CYCLES; ++cycle) {
    const double t = kPeriod * cycle / CYCLES;
    pnb_field_desc f = PNB_FIELD_DESC_INIT;
    move_points(t, x0, y0, x, y, speed);
    for (i = 0; i < NPTS; ++i) temperature[i] = temperature0[i] * (1.0 - 0.4 * t); /* the material cools */
    if (!check(ctx, pnb_publish_mesh(ctx, &mesh, PNB_BORROW), "pnb_publish_mesh")) {
      ++failures;
      break;
    }
    f.name = "temperature";
    f.values = temperature;
    f.count = NPTS;
    check(ctx, pnb_publish_field(ctx, &f, PNB_BORROW), "pnb_publish_field(temperature)");
    f.name = "speed";
    f.values = speed;
    check(ctx, pnb_publish_field(ctx, &f, PNB_BORROW), "pnb_publish_field(speed)");
    if (!check(ctx, pnb_execute(ctx, t, cycle), "pnb_execute")) ++failures;
  }
  if (!check(ctx, pnb_finalize(ctx), "pnb_finalize")) ++failures;
  pnb_destroy(ctx);
  printf("penumbra-example-lagrangian: %d hexahedra moving for %d cycles, 12 rendered steps x 2 fields x 2 cameras\n",
         NCELLS, CYCLES);
  printf("  Cinema database: %s/data.csv\n  compressed history: %s (penumbra-replay CONFIG %s)\n", out, store, store);
  return failures == 0 ? 0 : 1;
}
