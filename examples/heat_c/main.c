// SPDX-License-Identifier: BSD-3-Clause
/* examples/heat_c/main.c -- a plain C99 "solver" using Penumbra's C API.
 *
 * Heat conduction in a block of hexahedra made of two materials: a heater in one corner warms
 * the block while the far face is held cold. Temperature lives on the points; the material
 * conductivity is a cell field (Penumbra averages it to the points). Both are rendered.
 * Usage: penumbra-example-c [OUTPUT_DIR]   (default ./penumbra-example-c-db) */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "penumbra/penumbra.h"

enum { NX = 24, NY = 16, NZ = 12 };
#define NPTS ((NX + 1) * (NY + 1) * (NZ + 1))
#define NCELLS (NX * NY * NZ)

static int64_t node(int i, int j, int k) { return ((int64_t)k * (NY + 1) + j) * (NX + 1) + i; }

static int check(pnb_context ctx, pnb_status s, const char* what) {
  if (s == PNB_OK) return 1;
  fprintf(stderr, "penumbra-example-c: %s failed: %s\n", what, pnb_last_error(ctx));
  return 0;
}

int main(int argc, char** argv) {
  const char* out = argc > 1 ? argv[1] : "penumbra-example-c-db";
  static double xyz[NPTS * 3], temperature[NPTS], next[NPTS], conductivity[NCELLS], point_k[NPTS];
  static int64_t hexes[NCELLS * 8];
  static const uint8_t hex_type = PNB_HEXAHEDRON;
  char config[2048];
  pnb_context ctx = NULL;
  pnb_mesh_desc mesh = PNB_MESH_DESC_INIT;
  int i, j, k, c, cycle, failures = 0;
  const double h = 1.0 / NY;

  for (k = 0; k <= NZ; ++k)
    for (j = 0; j <= NY; ++j)
      for (i = 0; i <= NX; ++i) {
        const int64_t p = node(i, j, k);
        xyz[3 * p] = i * h;
        xyz[3 * p + 1] = j * h;
        xyz[3 * p + 2] = k * h;
        temperature[p] = 0.0;
      }
  c = 0;
  for (k = 0; k < NZ; ++k)
    for (j = 0; j < NY; ++j)
      for (i = 0; i < NX; ++i, ++c) {
        /* VTK hexahedron order: bottom quad counter-clockwise, then the top quad. */
        const int64_t v[8] = {node(i, j, k),     node(i + 1, j, k),     node(i + 1, j + 1, k),     node(i, j + 1, k),
                              node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)};
        memcpy(&hexes[8 * c], v, sizeof v);
        conductivity[c] = i < NX / 2 ? 1.0 : 0.2; /* a good and a poor conductor */
      }
  /* Per-point conductivity for the solver's own stencil: the mean of the touching cells. */
  for (i = 0; i < NPTS; ++i) point_k[i] = 0.0;
  {
    static int hits[NPTS];
    for (c = 0; c < NCELLS; ++c)
      for (k = 0; k < 8; ++k) {
        point_k[hexes[8 * c + k]] += conductivity[c];
        ++hits[hexes[8 * c + k]];
      }
    for (i = 0; i < NPTS; ++i) point_k[i] /= hits[i];
  }

  snprintf(config, sizeof config,
           "{\"output\": {\"directory\": \"%s\"},"
           " \"image\": {\"width\": 160, \"height\": 128, \"background\": [0.08, 0.08, 0.1]},"
           " \"cameras\": {\"phi\": [-50, 40], \"theta\": [25], \"fov\": 28},"
           " \"fields\": ["
           "   {\"name\": \"temperature\", \"range\": [0, 1], \"transfer_function\": {"
           "      \"colors\": [[0, 0.1, 0.1, 0.4], [0.4, 0.9, 0.3, 0.1], [1, 1, 1, 0.6]],"
           "      \"opacities\": [[0, 0.6], [0.1, 1], [1, 12]]}},"
           "   {\"name\": \"conductivity\", \"transfer_function\": {"
           "      \"colors\": [[0, 0.2, 0.5, 0.9], [1, 0.9, 0.8, 0.2]], \"opacities\": [[0, 1], [1, 3]]}}],"
           " \"trigger\": {\"every_cycles\": 100}}",
           out);
  if (!check(NULL, pnb_create(config, &ctx), "pnb_create")) return 1;

  mesh.points = xyz;
  mesh.point_count = NPTS;
  mesh.point_type = PNB_FLOAT64;
  mesh.connectivity = hexes;
  mesh.connectivity_count = NCELLS * 8;
  mesh.offsets = NULL; /* all cells are hexahedra */
  mesh.index_type = PNB_INT64;
  mesh.cell_types = &hex_type;
  mesh.cell_types_count = 1;
  mesh.topology_version = 1;
  if (!check(ctx, pnb_publish_mesh(ctx, &mesh, PNB_BORROW), "pnb_publish_mesh")) {
    pnb_destroy(ctx);
    return 1;
  }
  /* The conductivity does not change: publish it once as a copy, Penumbra keeps it. */
  {
    pnb_field_desc f = PNB_FIELD_DESC_INIT;
    f.name = "conductivity";
    f.association = PNB_CELL_FIELD;
    f.values = conductivity;
    f.count = NCELLS;
    check(ctx, pnb_publish_field(ctx, &f, PNB_COPY), "pnb_publish_field(conductivity)");
  }

  for (cycle = 0; cycle <= 1000; ++cycle) {
    const double dt = 0.12 * h * h; /* explicit diffusion limit h^2 / (6 k_max), with margin */
    pnb_field_desc t = PNB_FIELD_DESC_INIT;
    t.name = "temperature";
    t.values = temperature;
    t.count = NPTS;
    check(ctx, pnb_publish_field(ctx, &t, PNB_BORROW), "pnb_publish_field(temperature)");
    if (!check(ctx, pnb_execute(ctx, cycle * dt, cycle), "pnb_execute")) ++failures;

    for (k = 0; k <= NZ; ++k)
      for (j = 0; j <= NY; ++j)
        for (i = 0; i <= NX; ++i) {
          const int64_t p = node(i, j, k);
          /* Zero-flux walls: a missing neighbour mirrors the point itself. */
          const double tx0 = temperature[i > 0 ? node(i - 1, j, k) : p], tx1 = temperature[i < NX ? node(i + 1, j, k) : p];
          const double ty0 = temperature[j > 0 ? node(i, j - 1, k) : p], ty1 = temperature[j < NY ? node(i, j + 1, k) : p];
          const double tz0 = temperature[k > 0 ? node(i, j, k - 1) : p], tz1 = temperature[k < NZ ? node(i, j, k + 1) : p];
          next[p] = temperature[p] + dt * point_k[p] * (tx0 + tx1 + ty0 + ty1 + tz0 + tz1 - 6 * temperature[p]) / (h * h);
          if (i < 4 && j < 4 && k < 4) next[p] = 1.0; /* the heater */
          if (i == NX) next[p] = 0.0;                 /* the cold face */
        }
    memcpy(temperature, next, sizeof temperature);
  }
  if (!check(ctx, pnb_finalize(ctx), "pnb_finalize")) ++failures;
  pnb_destroy(ctx);
  printf("penumbra-example-c: %d hexahedra, 1001 cycles, 11 rendered steps x 2 fields x 2 cameras\n", NCELLS);
  printf("  Cinema database: %s/data.csv\n", out);
  return failures == 0 ? 0 : 1;
}
