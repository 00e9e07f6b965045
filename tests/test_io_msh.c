/* MSH files: exact number conversion, round trips of synthetic meshes of
 * orders 1, 2, 3, 5, 10 in every format the writer knows (4.1 and 2.2,
 * ASCII and binary, with and without parameters: positions bit-exact,
 * classification, parameters, connectivity), gmsh reads each of them alike,
 * we read gmsh's 4.1 and 2.2 files (ASCII and binary), hand-made binary
 * 4.1 and 2.2 files of both byte orders, and corrupt input of every kind
 * fails cleanly (HOC_ERR_FORMAT, or HOC_ERR_UNSUPPORTED for what
 * is valid but not handled).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "test_util.h"
#include "test_fixtures.h"

#include <gmshc.h>
#include <stdint.h>
#include <string.h>
#include <sys/stat.h>

#ifndef HOC_SOURCE_DIR
#define HOC_SOURCE_DIR "."
#endif

static uint64_t rng_state = 0x9E3779B97F4A7C15ULL;
static uint64_t rng(void) { /* xorshift64 */
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return rng_state;
}

/* MSH 4.1 ASCII with parametric coordinates */
static const hoc_msh_options param41 = {41, 0, 1};

static int same_bits(double a, double b) { return !memcmp(&a, &b, sizeof a); }

/* Numbers ------------------------------------------------------------------------ */

static int format_matches_printf(double v) {
  char mine[32], libc[64];
  hoc_io_format_double(v, mine);
  snprintf(libc, sizeof libc, "%.17g", v);
  double back;
  return !strcmp(mine, libc) && hoc_io_parse_double(mine, strlen(mine), &back) &&
         same_bits(back, v);
}

static int parse_matches_strtod(const char *s) {
  double a, b;
  char *end;
  int ok = hoc_io_parse_double(s, strlen(s), &a);
  b = strtod(s, &end);
  return ok == (*end == '\0' && end != s) && (!ok || same_bits(a, b));
}

static void test_numbers(void) {
  const double special[] = {0.5,
                            1,
                            1.5,
                            0.1,
                            1.0 / 3,
                            2.0 / 3,
                            1e16,
                            1e17,
                            99999999999999999.0,
                            9.9999999999999991e-5,
                            1e-4,
                            1e-5,
                            123456789012345678.0,
                            5e-324,
                            2.2250738585072014e-308,
                            1.7976931348623157e308,
                            1e22,
                            1e23,
                            0.30000000000000004,
                            9007199254740993.0,
                            -0.0,
                            0.0};
  int fmt_ok = 1, parse_ok = 1;
  for (size_t k = 0; k < sizeof special / sizeof *special; ++k)
    fmt_ok &= format_matches_printf(special[k]) && format_matches_printf(-special[k]);
  for (int e = -324; e <= 308; ++e) { /* powers of ten and their neighbours */
    char s[32];
    snprintf(s, sizeof s, "1e%d", e);
    double v = strtod(s, NULL);
    fmt_ok &= format_matches_printf(v) && format_matches_printf(nextafter(v, 0)) &&
              format_matches_printf(nextafter(v, INFINITY));
    parse_ok &= parse_matches_strtod(s);
  }
  for (int k = 0; k < 200000; ++k) {
    uint64_t bits = rng();
    double v;
    memcpy(&v, &bits, sizeof v);
    if (isfinite(v)) fmt_ok &= format_matches_printf(v);
    double w = (double)(rng() >> 11) * 0x1p-53 * 200 - 100; /* typical coordinates */
    fmt_ok &= format_matches_printf(w);
    char s[64];
    const char *formats[3] = {"%.16g", "%.6g", "%.20e"};
    snprintf(s, sizeof s, formats[k % 3], k % 2 ? w : v);
    if (isfinite(v)) parse_ok &= parse_matches_strtod(s);
  }
  CHECK(fmt_ok);
  CHECK(parse_ok);
  /* ties, long and odd spellings, non-numbers */
  const char *strings[] = {"9007199254740993",
                           "9007199254740995",
                           "2.4703282292062327e-324",
                           "1.00000000000000011102230246251565404236316680908203125",
                           "1e-400",
                           "123456789012345678901234567890",
                           ".5",
                           "5.",
                           "+3",
                           "-0",
                           "00012",
                           "1E5",
                           "1e+05",
                           "1e",
                           "1.2.3",
                           "--1",
                           ".",
                           "",
                           "e5",
                           "1e5x",
                           "0x10",
                           "nan",
                           "inf"};
  parse_ok = 1;
  for (size_t k = 0; k < sizeof strings / sizeof *strings; ++k)
    if (strcmp(strings[k], "0x10")) parse_ok &= parse_matches_strtod(strings[k]);
  CHECK(parse_ok);
  double v;
  CHECK(!hoc_io_parse_double("0x10", 4, &v));                   /* hexadecimal refused */
  CHECK(hoc_io_parse_double("2.5e3 junk", 5, &v) && v == 2500); /* only [0, n) is read */
}

/* Reference node lattice (gmsh ordering), built independently in
 * test_fixtures.h -------------------------------------------------------- */

static void test_lattice_is_gmsh(void) {
  int ok = 1;
  for (int p = 1; p <= 10; ++p) {
    int ij[2 * 66], np = (p + 1) * (p + 2) / 2, ierr = 0;
    CHECK(fixture_lattice(p, 0, 0, ij) == np);
    char *name = NULL;
    int dim, order, nn, nprim;
    double *lc = NULL;
    size_t nlc = 0;
    gmshModelMeshGetElementProperties(hoc_msh_triangle_type(p), &name, &dim, &order, &nn, &lc, &nlc,
                                      &nprim, &ierr);
    ok &= ierr == 0 && nn == np && order == p &&
          hoc_msh_element_nodes(hoc_msh_triangle_type(p)) == np;
    for (int k = 0; k < np && ok; ++k)
      ok &=
          fabs(lc[2 * k] * p - ij[2 * k]) < 1e-9 && fabs(lc[2 * k + 1] * p - ij[2 * k + 1]) < 1e-9;
    gmshFree(name);
    gmshFree(lc);
    ok &= hoc_msh_triangle_order(hoc_msh_triangle_type(p)) == p &&
          hoc_msh_line_order(hoc_msh_line_type(p)) == p &&
          hoc_msh_element_nodes(hoc_msh_line_type(p)) == p + 1;
  }
  CHECK(ok);
  CHECK(hoc_msh_triangle_type(0) == 0 && hoc_msh_triangle_type(11) == 0 &&
        hoc_msh_line_type(11) == 0);
  CHECK(hoc_msh_triangle_order(20) == -3 && hoc_msh_triangle_order(56) == -10);
  CHECK(hoc_msh_element_nodes(-1) == 0 && hoc_msh_element_nodes(5000) == 0);
}

/* A synthetic mesh ------------------------------------------------------------------
 * [0,2] x [0,1] in 4 x 2 cells of two order-p triangles each; surfaces 9
 * (x < 1) and 2 (x > 1); seven curves (the boundary in six pieces and the
 * line x = 1) and six points with unsorted tags; nodes on all of them with
 * parameters, lines of order p on every curve. Triangles are listed with
 * the two surfaces interleaved. */
enum { KX = 4, KY = 2, MAXP = 10 };
enum { MAXN = (KX * MAXP + 1) * (KY * MAXP + 1), MAXT = 2 * KX * KY, MAXL = 2 * (KX + KY) + KY };

typedef struct synth {
  int p;
  size_t nn, nt, nl;
  double xyz[3 * MAXN], par[2 * MAXN];
  int dim[MAXN], ent[MAXN];
  size_t tri[MAXT * 66], line[MAXL * 11];
  int tri_tag[MAXT], line_tag[MAXL];
  /* entities */
  int point_tag[6], curve_tag[7], surface_tag[2];
  double point_xyz[18], curve_bbox[42], surface_bbox[12];
  int curve_start[8], curve_bnd[14], surface_start[3], surface_bnd[12];
} synth;

static const int point_tags[6] = {11, 3, 7, 20, 5, 9}; /* (0,0) (1,0) (2,0) (2,1) (1,1) (0,1) */
static const int curve_tags[7] = {
    4, 12, 2, 30, 8, 6, 17}; /* bottom l, bottom r, right, top r, top l, left, middle */
static const int surface_tags[2] = {9, 2}; /* left, right */

/* Fine-lattice coordinates: I in [0, KX p], J in [0, KY p]. */
static void classify(const synth *m, int I, int J, int *dim, int *ent, double *par) {
  int p = m->p, Xm = 2 * p, Xe = KX * p, Ye = KY * p;
  double x = (double)I / Xe * 2, y = (double)J / Ye, pi = acos(-1.0);
  const int corner_I[6] = {0, Xm, Xe, Xe, Xm, 0}, corner_J[6] = {0, 0, 0, Ye, Ye, Ye};
  for (int k = 0; k < 6; ++k)
    if (I == corner_I[k] && J == corner_J[k]) {
      *dim = 0, *ent = point_tags[k], par[0] = par[1] = 0;
      return;
    }
  int c = -1;
  if (J == 0)
    c = I < Xm ? 0 : 1;
  else if (J == Ye)
    c = I < Xm ? 4 : 3;
  else if (I == Xe)
    c = 2;
  else if (I == 0)
    c = 5;
  else if (I == Xm)
    c = 6;
  if (c >= 0) {
    *dim = 1, *ent = curve_tags[c];
    par[0] = 0.1 + pi * (c == 2 || c == 5 || c == 6 ? y : x), par[1] = 0;
    return;
  }
  *dim = 2, *ent = surface_tags[I < Xm ? 0 : 1];
  par[0] = exp(1.0) * x - 1.0 / 7, par[1] = sqrt(2.0) * y + 1e-3;
}

static size_t node_at(synth *m, int *index, int I, int J) {
  int Ye = KY * m->p;
  int *slot = &index[I * (Ye + 1) + J];
  if (*slot >= 0) return (size_t)*slot;
  size_t i = m->nn++;
  double x = (double)I / (KX * m->p) * 2, y = (double)J / Ye;
  m->xyz[3 * i] = x;
  m->xyz[3 * i + 1] = y;
  m->xyz[3 * i + 2] = sin(3 * x) * cos(2 * y) / 3;
  classify(m, I, J, &m->dim[i], &m->ent[i], m->par + 2 * i);
  *slot = (int)i;
  return i;
}

static void build_synth(synth *m, int p) {
  memset(m, 0, sizeof *m);
  m->p = p;
  int np = (p + 1) * (p + 2) / 2, ij[2 * 66];
  fixture_lattice(p, 0, 0, ij);
  static int index[MAXN];
  for (int k = 0; k < MAXN; ++k)
    index[k] = -1;
  /* triangles, column by column so that the surfaces interleave by row */
  for (int cy = 0; cy < KY; ++cy)
    for (int cx = 0; cx < KX; ++cx)
      for (int up = 0; up < 2; ++up) {
        /* lower (0,0) (1,0) (0,1), upper (1,1) (0,1) (1,0) of the cell, both counterclockwise */
        int A[2] = {cx + up, cy + up}, B[2] = {cx + 1 - up, cy + up}, C[2] = {cx + up, cy + 1 - up};
        size_t e = m->nt++;
        for (int k = 0; k < np; ++k) {
          int I = A[0] * p + ij[2 * k] * (B[0] - A[0]) + ij[2 * k + 1] * (C[0] - A[0]);
          int J = A[1] * p + ij[2 * k] * (B[1] - A[1]) + ij[2 * k + 1] * (C[1] - A[1]);
          m->tri[e * (size_t)np + (size_t)k] = node_at(m, index, I, J);
        }
        m->tri_tag[e] = surface_tags[cx < 2 ? 0 : 1];
      }
  /* lines: every cell edge on a curve, in the curve's direction */
  for (int c = 0; c < 7; ++c) {
    int cells = c == 2 || c == 5 || c == 6 ? KY : 2;
    for (int s = 0; s < cells; ++s) {
      int I0, J0, dI, dJ; /* start cell corner and direction in cells */
      switch (c) {
      case 0: I0 = s, J0 = 0, dI = 1, dJ = 0; break;
      case 1: I0 = 2 + s, J0 = 0, dI = 1, dJ = 0; break;
      case 2: I0 = KX, J0 = s, dI = 0, dJ = 1; break;
      case 3: I0 = KX - s, J0 = KY, dI = -1, dJ = 0; break;
      case 4: I0 = 2 - s, J0 = KY, dI = -1, dJ = 0; break;
      case 5: I0 = 0, J0 = KY - s, dI = 0, dJ = -1; break;
      default: I0 = 2, J0 = s, dI = 0, dJ = 1; break;
      }
      size_t l = m->nl++, *ln = m->line + l * (size_t)(p + 1);
      ln[0] = node_at(m, index, I0 * p, J0 * p);
      ln[1] = node_at(m, index, (I0 + dI) * p, (J0 + dJ) * p);
      for (int k = 1; k < p; ++k)
        ln[1 + k] = node_at(m, index, I0 * p + k * dI, J0 * p + k * dJ);
      m->line_tag[l] = curve_tags[c];
    }
  }
  /* entities */
  static const int corner[6][2] = {{0, 0}, {2, 0}, {4, 0}, {4, 2}, {2, 2}, {0, 2}};
  for (int k = 0; k < 6; ++k) {
    m->point_tag[k] = point_tags[k];
    size_t i = node_at(m, index, corner[k][0] * p, corner[k][1] * p);
    memcpy(m->point_xyz + 3 * k, m->xyz + 3 * i, 3 * sizeof(double));
  }
  static const int ends[7][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 4}, {4, 5}, {5, 0}, {1, 4}};
  for (int c = 0; c < 7; ++c) {
    m->curve_tag[c] = curve_tags[c];
    m->curve_start[c] = 2 * c;
    m->curve_bnd[2 * c] = point_tags[ends[c][0]];
    m->curve_bnd[2 * c + 1] = -point_tags[ends[c][1]];
    double *bb = m->curve_bbox + 6 * c;
    for (int a = 0; a < 3; ++a) {
      double u = m->point_xyz[3 * ends[c][0] + a], v = m->point_xyz[3 * ends[c][1] + a];
      bb[a] = fmin(u, v) - 0.1, bb[3 + a] = fmax(u, v) + 0.1;
    }
  }
  m->curve_start[7] = 14;
  static const int loops[2][6] = {{4, 17, 8, 6, 0, 0}, {12, 2, 30, -17, 0, 0}};
  for (int s = 0; s < 2; ++s) {
    m->surface_tag[s] = surface_tags[s];
    m->surface_start[s] = 4 * s;
    for (int k = 0; k < 4; ++k)
      m->surface_bnd[4 * s + k] = loops[s][k];
    double *bb = m->surface_bbox + 6 * s;
    bb[0] = s ? 1 : 0, bb[1] = 0, bb[2] = -0.4, bb[3] = s ? 2 : 1, bb[4] = 1, bb[5] = 0.4;
  }
  m->surface_start[2] = 8;
}

static void fill_write_data(const synth *m, hoc_msh_write_data *d) {
  memset(d, 0, sizeof *d);
  d->n_points = 6, d->point_tag = m->point_tag, d->point_xyz = m->point_xyz;
  d->n_curves = 7, d->curve_tag = m->curve_tag, d->curve_bbox = m->curve_bbox;
  d->curve_bnd_start = m->curve_start, d->curve_bnd = m->curve_bnd;
  d->n_surfaces = 2, d->surface_tag = m->surface_tag, d->surface_bbox = m->surface_bbox;
  d->surface_bnd_start = m->surface_start, d->surface_bnd = m->surface_bnd;
  d->n_nodes = m->nn, d->xyz = m->xyz, d->param = m->par, d->node_dim = m->dim;
  d->node_entity_tag = m->ent;
  d->order = m->p, d->n_tris = m->nt, d->tri_nodes = m->tri, d->tri_surface_tag = m->tri_tag;
  d->n_lines = m->nl, d->line_nodes = m->line, d->line_curve_tag = m->line_tag;
}

/* Elements in file order: grouped by entity tag (ascending), stable. */
static size_t expected_order(size_t n, const int *tag, size_t *order) {
  size_t k = 0;
  int last = INT32_MIN;
  for (;;) {
    int next = INT32_MAX, found = 0;
    for (size_t e = 0; e < n; ++e)
      if (tag[e] > last && tag[e] <= next) next = tag[e], found = 1;
    if (!found) break;
    for (size_t e = 0; e < n; ++e)
      if (tag[e] == next) order[k++] = e;
    last = next;
  }
  return k;
}

/* Does raw equal m up to node numbering? map[our node] = raw node. */
static int same_mesh(const synth *m, const hoc_msh_raw *raw, int with_params, size_t *map) {
  int p = m->p, np = (p + 1) * (p + 2) / 2;
  if (raw->order != p || raw->n_tris != m->nt || raw->n_lines != m->nl || raw->n_nodes != m->nn)
    return 0;
  static size_t rev[MAXN];
  for (size_t i = 0; i < m->nn; ++i)
    map[i] = rev[i] = SIZE_MAX;
  size_t order[MAXT > MAXL ? MAXT : MAXL];
  int ok = 1;
  for (int kind = 0; kind < 2; ++kind) {
    size_t n = kind ? m->nl : m->nt, nper = kind ? (size_t)p + 1 : (size_t)np;
    const size_t *ours = kind ? m->line : m->tri, *theirs = kind ? raw->line_nodes : raw->tri_nodes;
    const int *tag = kind ? m->line_tag : m->tri_tag,
              *rtag = kind ? raw->line_curve_tag : raw->tri_surface_tag;
    expected_order(n, tag, order);
    for (size_t k = 0; k < n; ++k) {
      ok &= rtag[k] == tag[order[k]];
      for (size_t j = 0; j < nper; ++j) {
        size_t a = ours[order[k] * nper + j], b = theirs[k * nper + j];
        if (b >= raw->n_nodes) return 0;
        if (map[a] == SIZE_MAX && rev[b] == SIZE_MAX) map[a] = b, rev[b] = a;
        ok &= map[a] == b && rev[b] == a;
      }
    }
  }
  for (size_t a = 0; a < m->nn && ok; ++a) {
    size_t b = map[a];
    if (b == SIZE_MAX) return 0;
    for (int c = 0; c < 3; ++c)
      ok &= same_bits(raw->xyz[3 * b + (size_t)c], m->xyz[3 * a + (size_t)c]);
    ok &= raw->node_dim[b] == m->dim[a] && raw->node_entity_tag[b] == m->ent[a];
    if (with_params) {
      ok &= raw->has_param[b] == (m->dim[a] >= 1);
      for (int c = 0; c < m->dim[a]; ++c)
        ok &= same_bits(raw->param[2 * b + (size_t)c], m->par[2 * a + (size_t)c]);
    } else {
      ok &= !raw->has_param[b];
    }
  }
  return ok;
}

/* The file formats the writer knows, with a name suffix each. */
static const struct {
  hoc_msh_options o;
  const char *suffix;
} formats[] = {{{41, 0, 1}, "41_param"},    {{41, 0, 0}, "41"},       {{41, 1, 1}, "41bin_param"},
               {{41, 1, 0}, "41bin"},        {{22, 0, 0}, "22"},       {{22, 0, 1}, "22_param"},
               {{22, 1, 0}, "22bin"},        {{22, 1, 1}, "22bin_param"}};

/* gmsh reads our file: same nodes (bit-exact), classification, parameters
 * (parametric files), elements. */
static void check_gmsh_reads(const synth *m, const hoc_msh_raw *raw, const char *path,
                             int parametric) {
  int p = m->p, ierr = 0;
  gmshClear(&ierr);
  gmshOpen(path, &ierr);
  CHECK(ierr == 0);
  size_t *tags = NULL, ntags = 0, ncoord = 0, npar = 0;
  double *coord = NULL, *par = NULL;
  gmshModelMeshGetNodes(&tags, &ntags, &coord, &ncoord, &par, &npar, -1, -1, 0, 0, &ierr);
  int nodes_ok = ierr == 0 && ntags == raw->n_nodes;
  for (size_t k = 0; k < ntags && nodes_ok; ++k) {
    size_t j = tags[k] - 1;
    nodes_ok &= j < raw->n_nodes;
    for (int c = 0; c < 3 && nodes_ok; ++c)
      nodes_ok &= same_bits(coord[3 * k + (size_t)c], raw->xyz[3 * j + (size_t)c]);
  }
  CHECK(nodes_ok);
  gmshFree(tags), gmshFree(coord), gmshFree(par);
  int params_ok = 1;
  for (int dim = 0; dim <= 2; ++dim)
    for (int k = 0; k < (dim == 0 ? 6 : dim == 1 ? 7 : 2); ++k) {
      int etag = dim == 0 ? point_tags[k] : dim == 1 ? curve_tags[k] : surface_tags[k];
      gmshModelMeshGetNodes(&tags, &ntags, &coord, &ncoord, &par, &npar, dim, etag, 0, parametric,
                            &ierr);
      params_ok &= ierr == 0 && npar == (parametric ? (size_t)dim * ntags : 0);
      size_t expect = 0;
      for (size_t i = 0; i < raw->n_nodes; ++i)
        expect += raw->node_dim[i] == dim && raw->node_entity_tag[i] == etag;
      params_ok &= ntags == expect;
      for (size_t q = 0; q < ntags && params_ok; ++q) {
        size_t j = tags[q] - 1;
        params_ok &= j < raw->n_nodes && raw->node_dim[j] == dim && raw->node_entity_tag[j] == etag;
        for (int c = 0; c < dim && params_ok && parametric; ++c)
          params_ok &= same_bits(par[(size_t)dim * q + (size_t)c], raw->param[2 * j + (size_t)c]);
      }
      gmshFree(tags), gmshFree(coord), gmshFree(par);
    }
  if (!params_ok) fprintf(stderr, "gmsh classifies the nodes of %s otherwise\n", path);
  CHECK(params_ok);
  int np = (p + 1) * (p + 2) / 2;
  size_t *et = NULL, net = 0, *en = NULL, nen = 0;
  gmshModelMeshGetElementsByType(hoc_msh_triangle_type(p), &et, &net, &en, &nen, -1, 0, 1, &ierr);
  int elems_ok = ierr == 0 && net == m->nt && nen == m->nt * (size_t)np;
  for (size_t k = 0; k < nen && elems_ok; ++k)
    elems_ok &= en[k] == raw->node_tag[raw->tri_nodes[k]];
  gmshFree(et), gmshFree(en);
  gmshModelMeshGetElementsByType(hoc_msh_line_type(p), &et, &net, &en, &nen, -1, 0, 1, &ierr);
  elems_ok &= ierr == 0 && net == m->nl && nen == m->nl * (size_t)(p + 1);
  gmshFree(et), gmshFree(en);
  CHECK(elems_ok);
  int *dimtags = NULL;
  size_t ndt = 0;
  gmshModelGetEntities(&dimtags, &ndt, -1, &ierr);
  CHECK(ierr == 0 && ndt == 2 * (6 + 7 + 2));
  gmshFree(dimtags);
}

static void test_round_trip(int p) {
  static synth m;
  build_synth(&m, p);
  hoc_msh_write_data d;
  fill_write_data(&m, &d);
  for (size_t f = 0; f < sizeof formats / sizeof *formats; ++f) {
    const hoc_msh_options *o = &formats[f].o;
    char path[64];
    snprintf(path, sizeof path, "synth_p%d_%s.msh", p, formats[f].suffix);
    CHECK_OK(hoc_msh_write(path, &d, o));
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read(path, &raw));
    static size_t map[MAXN];
    int same = same_mesh(&m, &raw, o->parametric, map);
    if (!same) fprintf(stderr, "%s does not read back as written\n", path);
    CHECK(same);
    /* tags 1..n in file order, blocks sorted by (dim, entity tag) */
    int tags_ok = 1, sorted = 1;
    for (size_t j = 0; j < raw.n_nodes; ++j) {
      tags_ok &= raw.node_tag[j] == j + 1;
      if (j) {
        int d0 = raw.node_dim[j - 1], d1 = raw.node_dim[j];
        sorted &= d0 < d1 || (d0 == d1 && raw.node_entity_tag[j - 1] <= raw.node_entity_tag[j]);
      }
    }
    CHECK(tags_ok);
    CHECK(sorted);
    check_gmsh_reads(&m, &raw, path, o->parametric);
    hoc_msh_raw_free(&raw);
    CHECK(raw.xyz == NULL && raw.n_nodes == 0 && raw.tri_nodes == NULL);
  }
  /* the default is MSH 4.1 ASCII without parameters */
  char path[64], ref[64];
  snprintf(path, sizeof path, "synth_p%d_default.msh", p);
  snprintf(ref, sizeof ref, "synth_p%d_41.msh", p);
  CHECK_OK(hoc_msh_write(path, &d, NULL));
  size_t n1, n2;
  char *a = fixture_slurp(path, &n1), *b = fixture_slurp(ref, &n2);
  CHECK(a && b && n1 == n2 && !memcmp(a, b, n1));
  free(a);
  free(b);
}

/* Numbers at the edges of the double range survive bit for bit. */
static void test_special_values(void) {
  double xyz[9] = {-0.0,    5e-324, 1.7976931348623157e308, -2.2250738585072014e-308, 1e-300, 0.1,
                   1.0 / 3, -1e22,  123456789.125};
  double par[6] = {0, 0, -0.0, 0, 4.9406564584124654e-324, -1e300};
  int dim[3] = {0, 1, 2}, ent[3] = {1, 1, 1}, ptag = 1, ctag = 1, stag = 1, start[2] = {0, 0};
  double pxyz[3] = {0, 0, 0}, bb[6] = {-1, -1, -1, 1, 1, 1};
  size_t tri[3] = {0, 1, 2}, line[2] = {1, 0};
  int tri_tag = 1, line_tag = 1;
  hoc_msh_write_data d = {0};
  d.n_points = 1, d.point_tag = &ptag, d.point_xyz = pxyz;
  d.n_curves = 1, d.curve_tag = &ctag, d.curve_bbox = bb, d.curve_bnd_start = start;
  d.n_surfaces = 1, d.surface_tag = &stag, d.surface_bbox = bb, d.surface_bnd_start = start;
  d.n_nodes = 3, d.xyz = xyz, d.param = par, d.node_dim = dim, d.node_entity_tag = ent;
  d.order = 1, d.n_tris = 1, d.tri_nodes = tri, d.tri_surface_tag = &tri_tag;
  d.n_lines = 1, d.line_nodes = line, d.line_curve_tag = &line_tag;
  CHECK_OK(hoc_msh_write("special.msh", &d, &param41));
  hoc_msh_raw raw;
  CHECK_OK(hoc_msh_read("special.msh", &raw));
  int ok = raw.n_nodes == 3;
  for (size_t k = 0; k < 9 && ok; ++k)
    ok &= same_bits(raw.xyz[k], xyz[k]);
  ok = ok && same_bits(raw.param[2], par[2]) && same_bits(raw.param[4], par[4]) &&
       same_bits(raw.param[5], par[5]);
  ok = ok && raw.n_lines == 1 && raw.line_nodes[0] == 1 && raw.line_nodes[1] == 0;
  CHECK(ok);
  hoc_msh_raw_free(&raw);
}

/* The writer refuses bad input before creating anything. */
static void test_write_arguments(void) {
  static synth m;
  build_synth(&m, 2);
  hoc_msh_write_data d;
  fill_write_data(&m, &d);
  FILE *f = fopen("keep.msh", "w");
  fputs("previous", f);
  fclose(f);
  d.order = 11;
  CHECK_STATUS(hoc_msh_write("p11.msh", &d, &param41), HOC_ERR_UNSUPPORTED);
  d.order = 0;
  CHECK_STATUS(hoc_msh_write("p0.msh", &d, &param41), HOC_ERR_ARGUMENT);
  struct stat st;
  CHECK(stat("p11.msh", &st) != 0 && stat("p0.msh", &st) != 0);
  d.order = 2;
  double saved = m.xyz[7];
  m.xyz[7] = NAN;
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.xyz[7] = INFINITY;
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.xyz[7] = saved;
  size_t k = 0;
  while (m.dim[k] != 2)
    ++k;
  m.par[2 * k + 1] = NAN;
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.par[2 * k + 1] = 0;
  m.ent[k] = 1000; /* no such surface */
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.ent[k] = surface_tags[0];
  m.tri[5] = m.nn; /* no such node */
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.tri[5] = 0;
  m.curve_tag[3] = m.curve_tag[4]; /* listed twice */
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.curve_tag[3] = curve_tags[3];
  m.surface_bbox[2] = NAN;
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  m.surface_bbox[2] = 0;
  CHECK_STATUS(hoc_msh_write("no/such/dir/x.msh", &d, &param41), HOC_ERR_IO);
  CHECK_STATUS(hoc_msh_write("keep.msh", NULL, &param41), HOC_ERR_ARGUMENT);
  /* options out of range, parameters asked for but not given, 2.2's int tags */
  const hoc_msh_options bad_options[] = {{40, 0, 0}, {4, 0, 0}, {22, 2, 0}, {41, -1, 0},
                                         {41, 0, 2}, {22, 0, -1}};
  for (size_t b = 0; b < sizeof bad_options / sizeof *bad_options; ++b)
    CHECK_STATUS(hoc_msh_write("keep.msh", &d, &bad_options[b]), HOC_ERR_ARGUMENT);
  d.param = NULL;
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &param41), HOC_ERR_ARGUMENT);
  CHECK(strstr(hoc_last_error(), "parametric") != NULL);
  const hoc_msh_options plain22 = {22, 0, 0};
  d.n_nodes = (size_t)INT32_MAX + 1; /* refused before any node is looked at */
  CHECK_STATUS(hoc_msh_write("keep.msh", &d, &plain22), HOC_ERR_UNSUPPORTED);
  CHECK(strstr(hoc_last_error(), "2.2") != NULL);
  fill_write_data(&m, &d);
  f = fopen("keep.msh", "r");
  char buf[16] = {0};
  CHECK(f && fread(buf, 1, sizeof buf - 1, f) == 8 && !strcmp(buf, "previous"));
  if (f) fclose(f);
  /* an empty mesh is a valid file */
  hoc_msh_write_data e = {0};
  e.order = 3;
  CHECK_OK(hoc_msh_write("empty.msh", &e, &param41));
  hoc_msh_raw raw;
  CHECK_OK(hoc_msh_read("empty.msh", &raw));
  CHECK(raw.n_nodes == 0 && raw.n_tris == 0 && raw.order == 0);
  hoc_msh_raw_free(&raw);
}

/* Files gmsh writes ------------------------------------------------------------------- */

/* Put the synthetic order-3 mesh into gmsh with sparse, shuffled node tags;
 * gmsh_tag[i] is the tag of our node i. */
static void synth_to_gmsh(const synth *m, size_t *gmsh_tag) {
  int ierr = 0;
  gmshClear(&ierr);
  gmshModelAdd("synth", &ierr);
  size_t perm[MAXN];
  for (size_t i = 0; i < m->nn; ++i)
    perm[i] = i;
  for (size_t i = m->nn - 1; i > 0; --i) {
    size_t j = rng() % (i + 1), t = perm[i];
    perm[i] = perm[j], perm[j] = t;
  }
  for (size_t i = 0; i < m->nn; ++i)
    gmsh_tag[i] = 1 + 100003 * perm[i];
  int bnd[14];
  for (int k = 0; k < 6; ++k)
    gmshModelAddDiscreteEntity(0, m->point_tag[k], NULL, 0, &ierr);
  memcpy(bnd, m->curve_bnd, sizeof bnd);
  for (int c = 0; c < 7; ++c)
    gmshModelAddDiscreteEntity(1, m->curve_tag[c], bnd + 2 * c, 2, &ierr);
  memcpy(bnd, m->surface_bnd, 8 * sizeof *bnd);
  for (int s = 0; s < 2; ++s)
    gmshModelAddDiscreteEntity(2, m->surface_tag[s], bnd + 4 * s, 4, &ierr);
  CHECK(ierr == 0);
  static size_t tags[MAXN];
  static double xyz[3 * MAXN], par[2 * MAXN];
  for (int dim = 0; dim <= 2; ++dim) {
    int ne = dim == 0 ? 6 : dim == 1 ? 7 : 2;
    for (int k = 0; k < ne; ++k) {
      int etag = dim == 0 ? m->point_tag[k] : dim == 1 ? m->curve_tag[k] : m->surface_tag[k];
      size_t n = 0;
      for (size_t i = 0; i < m->nn; ++i) {
        if (m->dim[i] != dim || m->ent[i] != etag) continue;
        tags[n] = gmsh_tag[i];
        memcpy(xyz + 3 * n, m->xyz + 3 * i, 3 * sizeof(double));
        for (int c = 0; c < dim; ++c)
          par[(size_t)dim * n + (size_t)c] = m->par[2 * i + (size_t)c];
        ++n;
      }
      gmshModelMeshAddNodes(dim, etag, tags, n, xyz, 3 * n, par, (size_t)dim * n, &ierr);
      if (dim == 0) {
        size_t et = 900000 + (size_t)k;
        gmshModelMeshAddElementsByType(etag, 15, &et, 1, tags, 1, &ierr);
      }
    }
  }
  CHECK(ierr == 0);
  int p = m->p, np = (p + 1) * (p + 2) / 2;
  static size_t etags[MAXT], enodes[MAXT * 66];
  size_t next = 1;
  for (int kind = 1; kind <= 2; ++kind) {
    int ne = kind == 1 ? 7 : 2;
    size_t nper = kind == 1 ? (size_t)p + 1 : (size_t)np, nel = kind == 1 ? m->nl : m->nt;
    for (int k = 0; k < ne; ++k) {
      int etag = kind == 1 ? m->curve_tag[k] : m->surface_tag[k];
      size_t n = 0;
      for (size_t e = 0; e < nel; ++e) {
        if ((kind == 1 ? m->line_tag[e] : m->tri_tag[e]) != etag) continue;
        etags[n] = next++;
        for (size_t j = 0; j < nper; ++j)
          enodes[n * nper + j] = gmsh_tag[(kind == 1 ? m->line : m->tri)[e * nper + j]];
        ++n;
      }
      gmshModelMeshAddElementsByType(etag,
                                     kind == 1 ? hoc_msh_line_type(p) : hoc_msh_triangle_type(p),
                                     etags, n, enodes, n * nper, &ierr);
    }
  }
  CHECK(ierr == 0);
}

/* gmsh writes ASCII numbers with "%.16g": equal to 16 digits, not bit for bit. */
static int close16(double a, double b) { return fabs(a - b) <= 1e-15 * fmax(1, fabs(b)); }

/* Compare a file gmsh wrote with our synthetic mesh, matching nodes by
 * position (MSH 2.2 renumbers them). */
static int same_as_gmsh_file(const synth *m, const hoc_msh_raw *raw, const size_t *gmsh_tag,
                             int keeps_tags, int with_params) {
  int p = m->p, np = (p + 1) * (p + 2) / 2,
      ok =
          raw->order == p && raw->n_nodes == m->nn && raw->n_tris == m->nt && raw->n_lines == m->nl;
  static size_t ours[MAXN]; /* raw node -> our node */
  for (size_t j = 0; j < raw->n_nodes && ok; ++j) {
    size_t a = SIZE_MAX;
    for (size_t i = 0; i < m->nn; ++i)
      if (close16(raw->xyz[3 * j], m->xyz[3 * i]) &&
          close16(raw->xyz[3 * j + 1], m->xyz[3 * i + 1]) &&
          close16(raw->xyz[3 * j + 2], m->xyz[3 * i + 2]))
        a = i;
    ok &= a != SIZE_MAX;
    if (!ok) break;
    ours[j] = a;
    if (keeps_tags) ok &= raw->node_tag[j] == gmsh_tag[a];
    ok &= raw->node_dim[j] == m->dim[a] && raw->node_entity_tag[j] == m->ent[a];
    ok &= raw->has_param[j] == (with_params && m->dim[a] >= 1);
    if (with_params)
      for (int c = 0; c < m->dim[a]; ++c)
        ok &= close16(raw->param[2 * j + (size_t)c], m->par[2 * a + (size_t)c]);
  }
  /* every triangle of the file is one of ours, nodes in the same order */
  for (size_t e = 0; e < raw->n_tris && ok; ++e) {
    int found = 0;
    for (size_t f = 0; f < m->nt && !found; ++f) {
      int same = raw->tri_surface_tag[e] == m->tri_tag[f];
      for (int k = 0; k < np && same; ++k)
        same =
            ours[raw->tri_nodes[e * (size_t)np + (size_t)k]] == m->tri[f * (size_t)np + (size_t)k];
      found = same;
    }
    ok &= found;
  }
  return ok;
}

static void test_gmsh_written(void) {
  static synth m;
  static size_t gmsh_tag[MAXN];
  build_synth(&m, 3);
  synth_to_gmsh(&m, gmsh_tag);
  struct {
    const char *file;
    int binary;
    double version;
    int parametric;
  } files[] = {{"gmsh41.msh", 0, 4.1, 1},
               {"gmsh41bin.msh", 1, 4.1, 1},
               {"gmsh41plain.msh", 0, 4.1, 0},
               {"gmsh22.msh", 0, 2.2, 0},
               {"gmsh22param.msh", 0, 2.2, 1},
               {"gmsh22bin.msh", 1, 2.2, 0},
               {"gmsh22parambin.msh", 1, 2.2, 1}};
  int ierr = 0;
  for (size_t f = 0; f < sizeof files / sizeof *files; ++f) {
    gmshOptionSetNumber("Mesh.Binary", files[f].binary, &ierr);
    gmshOptionSetNumber("Mesh.MshFileVersion", files[f].version, &ierr);
    gmshOptionSetNumber("Mesh.SaveParametric", files[f].parametric, &ierr);
    gmshWrite(files[f].file, &ierr);
    CHECK(ierr == 0);
  }
  gmshOptionSetNumber("Mesh.Binary", 0, &ierr);
  gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr);
  gmshOptionSetNumber("Mesh.SaveParametric", 0, &ierr);
  for (size_t f = 0; f < sizeof files / sizeof *files; ++f) {
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read(files[f].file, &raw));
    int v4 = files[f].version > 4;
    /* gmsh 4.1 without SaveParametric still classifies; 2.2 classifies through elements */
    if (!same_as_gmsh_file(&m, &raw, gmsh_tag, v4, files[f].parametric))
      fprintf(stderr, "mismatch reading %s\n", files[f].file);
    CHECK(same_as_gmsh_file(&m, &raw, gmsh_tag, v4, files[f].parametric));
    hoc_msh_raw_free(&raw);
  }
}

/* Real gmsh meshes from the fuzz corpus (meshed by gmsh, order 2). */
static void test_corpus(void) {
  const char *names[3] = {"gmsh41_p2.msh", "gmsh41bin_p2.msh", "gmsh22_p2.msh"};
  size_t counts[3][3] = {{0}};
  for (int k = 0; k < 3; ++k) {
    char path[512];
    snprintf(path, sizeof path, "%s/tests/fuzz/corpus/%s", HOC_SOURCE_DIR, names[k]);
    FILE *f = fopen(path, "rb");
    if (!f) continue; /* not found from this directory */
    fclose(f);
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read(path, &raw));
    CHECK(raw.order == 2 && raw.n_tris > 0);
    int classified = 1;
    for (size_t i = 0; i < raw.n_nodes; ++i)
      classified &= raw.node_dim[i] >= 0 && raw.node_dim[i] <= 2;
    CHECK(classified);
    counts[k][0] = raw.n_nodes, counts[k][1] = raw.n_tris, counts[k][2] = raw.n_lines;
    hoc_msh_raw_free(&raw);
  }
  if (counts[0][1] && counts[1][1]) CHECK(!memcmp(counts[0], counts[1], sizeof counts[0]));
}

/* Hand-made binary files ---------------------------------------------------------------- */

typedef struct bytes {
  char data[4096];
  size_t n;
  int big;   /* big-endian fields */
  int dsize; /* size_t fields: 4 or 8 bytes */
} bytes;

static void b_raw(bytes *b, const void *p, size_t n) {
  memcpy(b->data + b->n, p, n);
  b->n += n;
}
static void b_str(bytes *b, const char *s) { b_raw(b, s, strlen(s)); }
static void b_field(bytes *b, const void *p, size_t n) {
  unsigned char t[8];
  memcpy(t, p, n);
  const uint16_t one = 1;
  int little_host = *(const unsigned char *)&one == 1;
  if (little_host == b->big)
    for (size_t i = 0; i < n / 2; ++i) {
      unsigned char c = t[i];
      t[i] = t[n - 1 - i], t[n - 1 - i] = c;
    }
  b_raw(b, t, n);
}
static void b_int(bytes *b, int32_t v) { b_field(b, &v, 4); }
static void b_size(bytes *b, uint64_t v) {
  if (b->dsize == 4) {
    uint32_t w = (uint32_t)v;
    b_field(b, &w, 4);
  } else {
    b_field(b, &v, 8);
  }
}
static void b_real(bytes *b, double v) { b_field(b, &v, 8); }

/* One order-1 triangle on surface 5 (nodes 10, 20, 30, parametric), one line
 * on curve 3, one point element; `n_nodes` in the header may lie. */
static void make_binary(bytes *b, int big, int dsize, uint64_t n_nodes, double x0) {
  memset(b, 0, sizeof *b);
  b->big = big, b->dsize = dsize;
  char head[64];
  snprintf(head, sizeof head, "$MeshFormat\n4.1 1 %d\n", dsize);
  b_str(b, head);
  b_int(b, 1);
  b_str(b, "\n$EndMeshFormat\n$Nodes\n");
  b_size(b, 2), b_size(b, n_nodes), b_size(b, 10), b_size(b, 30);
  b_int(b, 1), b_int(b, 3), b_int(b, 1), b_size(b, 1); /* node 30 on curve 3 */
  b_size(b, 30);
  b_real(b, 0), b_real(b, 1), b_real(b, 0), b_real(b, 0.75);
  b_int(b, 2), b_int(b, 5), b_int(b, 1), b_size(b, 2);
  b_size(b, 10), b_size(b, 20);
  b_real(b, x0), b_real(b, 0), b_real(b, 0), b_real(b, 0.25), b_real(b, 0.5);
  b_real(b, 1), b_real(b, 0), b_real(b, 0), b_real(b, 1.25), b_real(b, 1.5);
  b_str(b, "\n$EndNodes\n$Elements\n");
  b_size(b, 3), b_size(b, 3), b_size(b, 1), b_size(b, 3);
  b_int(b, 0), b_int(b, 1), b_int(b, 15), b_size(b, 1);
  b_size(b, 1), b_size(b, 30);
  b_int(b, 1), b_int(b, 3), b_int(b, 1), b_size(b, 1);
  b_size(b, 2), b_size(b, 20), b_size(b, 30);
  b_int(b, 2), b_int(b, 5), b_int(b, 2), b_size(b, 1);
  b_size(b, 3), b_size(b, 10), b_size(b, 20), b_size(b, 30);
  b_str(b, "\n$EndElements\n");
}

static void test_binary_variants(void) {
  bytes b;
  for (int big = 0; big < 2; ++big)
    for (int dsize = 4; dsize <= 8; dsize += 4) {
      make_binary(&b, big, dsize, 3, 0.125);
      hoc_msh_raw raw;
      CHECK_OK(hoc_msh_read_buffer(b.data, b.n, "handmade", &raw));
      int ok = raw.order == 1 && raw.n_nodes == 3 && raw.n_tris == 1 && raw.n_lines == 1;
      if (ok) {
        /* file order: node 30 (curve), then 10 and 20 (surface) */
        ok &= raw.node_tag[0] == 30 && raw.node_tag[1] == 10 && raw.node_tag[2] == 20;
        ok &= raw.tri_nodes[0] == 1 && raw.tri_nodes[1] == 2 && raw.tri_nodes[2] == 0;
        ok &= raw.line_nodes[0] == 2 && raw.line_nodes[1] == 0 && raw.line_curve_tag[0] == 3;
        ok &= raw.xyz[3] == 0.125 && raw.param[2] == 0.25 && raw.param[3] == 0.5 &&
              raw.param[0] == 0.75;
        ok &= raw.node_dim[0] == 1 && raw.node_dim[1] == 2 && raw.node_entity_tag[1] == 5;
        ok &= raw.has_param[0] && raw.has_param[1] && raw.tri_surface_tag[0] == 5;
      }
      CHECK(ok);
      hoc_msh_raw_free(&raw);
      /* huge and absurd counts, NaN */
      const uint64_t lies[3] = {UINT64_C(1) << 40, UINT64_C(1) << 62, (UINT64_C(1) << 63) + 5};
      for (int k = 0; k < 3; ++k) {
        if (dsize == 4 && k) continue;
        make_binary(&b, big, dsize, lies[k], 0.125);
        CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "huge", &raw), HOC_ERR_FORMAT);
      }
      make_binary(&b, big, dsize, 3, NAN);
      CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "nan", &raw), HOC_ERR_FORMAT);
      CHECK(strstr(hoc_last_error(), "$Nodes") != NULL);
    }
}

/* The same mesh as binary MSH 2.2 (ints for tags, counts on text lines):
 * parametric nodes 30 (curve 3), 10 and 20 (surface 5), then a point on
 * node 30 (point 4), the line and the triangle in blocks of (type, count,
 * 2 tags); `n_elems` in the header may lie, `ntags` is the tags per element. */
static void make_binary22(bytes *b, int big, uint64_t n_elems, int ntags, int node) {
  memset(b, 0, sizeof *b);
  b->big = big, b->dsize = 8;
  b_str(b, "$MeshFormat\n2.2 1 8\n");
  b_int(b, 1);
  b_str(b, "\n$EndMeshFormat\n$ParametricNodes\n3\n");
  b_int(b, 30), b_real(b, 0), b_real(b, 1), b_real(b, 0), b_int(b, 1), b_int(b, 3);
  b_real(b, 0.75);
  b_int(b, 10), b_real(b, 0.125), b_real(b, 0), b_real(b, 0), b_int(b, 2), b_int(b, 5);
  b_real(b, 0.25), b_real(b, 0.5);
  b_int(b, 20), b_real(b, 1), b_real(b, 0), b_real(b, 0), b_int(b, 2), b_int(b, 5);
  b_real(b, 1.25), b_real(b, 1.5);
  char head[64];
  snprintf(head, sizeof head, "\n$EndParametricNodes\n$Elements\n%llu\n",
           (unsigned long long)n_elems);
  b_str(b, head);
  b_int(b, 15), b_int(b, 1), b_int(b, ntags);
  b_int(b, 1);
  for (int t = 0; t < ntags; ++t)
    b_int(b, t == 1 ? 4 : 0);
  b_int(b, node);
  b_int(b, 1), b_int(b, 1), b_int(b, ntags);
  b_int(b, 2);
  for (int t = 0; t < ntags; ++t)
    b_int(b, t == 1 ? 3 : 0);
  b_int(b, 20), b_int(b, 30);
  b_int(b, 2), b_int(b, 1), b_int(b, ntags);
  b_int(b, 3);
  for (int t = 0; t < ntags; ++t)
    b_int(b, t == 1 ? 5 : 7);
  b_int(b, 10), b_int(b, 20), b_int(b, 30);
  b_str(b, "\n$EndElements\n");
}

static void test_binary22(void) {
  bytes b;
  for (int big = 0; big < 2; ++big) {
    make_binary22(&b, big, 3, 2, 30);
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read_buffer(b.data, b.n, "handmade22", &raw));
    int ok = raw.order == 1 && raw.n_nodes == 3 && raw.n_tris == 1 && raw.n_lines == 1;
    if (ok) {
      ok &= raw.node_tag[0] == 30 && raw.node_tag[1] == 10 && raw.node_tag[2] == 20;
      ok &= raw.tri_nodes[0] == 1 && raw.tri_nodes[1] == 2 && raw.tri_nodes[2] == 0;
      ok &= raw.line_nodes[0] == 2 && raw.line_nodes[1] == 0 && raw.line_curve_tag[0] == 3;
      ok &= raw.xyz[3] == 0.125 && raw.param[2] == 0.25 && raw.param[3] == 0.5 &&
            raw.param[0] == 0.75;
      /* $ParametricNodes classify: node 30 stays on curve 3 despite the point element */
      ok &= raw.node_dim[0] == 1 && raw.node_entity_tag[0] == 3;
      ok &= raw.node_dim[1] == 2 && raw.node_entity_tag[1] == 5 && raw.tri_surface_tag[0] == 5;
      ok &= raw.has_param[0] && raw.has_param[1];
    }
    CHECK(ok);
    hoc_msh_raw_free(&raw);
    /* three tags (a partition count) per element are read past */
    make_binary22(&b, big, 3, 3, 30);
    CHECK_OK(hoc_msh_read_buffer(b.data, b.n, "tags22", &raw));
    CHECK(raw.n_tris == 1 && raw.tri_surface_tag[0] == 5 && raw.line_curve_tag[0] == 3);
    hoc_msh_raw_free(&raw);
    /* counts that lie, negative tags, unknown nodes */
    make_binary22(&b, big, 4, 2, 30);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "more22", &raw), HOC_ERR_FORMAT);
    make_binary22(&b, big, 2, 2, 30);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "fewer22", &raw), HOC_ERR_FORMAT);
    make_binary22(&b, big, UINT64_C(1) << 40, 2, 30);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "huge22", &raw), HOC_ERR_FORMAT);
    CHECK(strstr(hoc_last_error(), "more than the rest") != NULL);
    make_binary22(&b, big, 3, -1, 30);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "ntags22", &raw), HOC_ERR_FORMAT);
    make_binary22(&b, big, 3, 2, -30);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "negative22", &raw), HOC_ERR_FORMAT);
    make_binary22(&b, big, 3, 2, 31);
    CHECK_STATUS(hoc_msh_read_buffer(b.data, b.n, "unknown22", &raw), HOC_ERR_FORMAT);
    CHECK(strstr(hoc_last_error(), "node 31") != NULL);
  }
}

/* Corrupt input ------------------------------------------------------------------------- */

/* A successful read must be self-consistent. */
static int raw_is_consistent(const hoc_msh_raw *raw) {
  int p = raw->order, np = (p + 1) * (p + 2) / 2;
  if (raw->n_tris && (p < 1 || p > 10)) return 0;
  for (size_t k = 0; k < raw->n_tris * (size_t)np; ++k)
    if (raw->tri_nodes[k] >= raw->n_nodes) return 0;
  for (size_t k = 0; k < raw->n_lines * (size_t)(p + 1); ++k)
    if (raw->line_nodes[k] >= raw->n_nodes) return 0;
  for (size_t i = 0; i < 3 * raw->n_nodes; ++i)
    if (!isfinite(raw->xyz[i])) return 0;
  return 1;
}

static void test_corrupt_file(const char *path) {
  size_t n;
  char *d = fixture_slurp(path, &n);
  CHECK(d != NULL && n > 0);
  if (!d) return;
  const char *end_marker = "$EndElements";
  size_t whole = 0; /* shortest prefix that is still the whole mesh */
  for (size_t k = 0; k + strlen(end_marker) <= n; ++k)
    if (!memcmp(d + k, end_marker, strlen(end_marker))) whole = k + strlen(end_marker);
  hoc_msh_raw raw;
  int clean = 1;
  size_t step = n > 3000 ? n / 1500 : 1;
  for (size_t len = 0; len < n; len += len < 300 || len + 300 > n ? 1 : step) {
    hoc_status st = hoc_msh_read_buffer(d, len, "truncated", &raw);
    if (st == HOC_OK) {
      clean &= len >= whole && raw_is_consistent(&raw);
      hoc_msh_raw_free(&raw);
    } else {
      clean &= st == HOC_ERR_FORMAT && len < whole;
    }
  }
  if (!clean) fprintf(stderr, "truncating %s: unclean result\n", path);
  CHECK(clean);
  /* random bytes overwritten, fixed seed */
  char *c = malloc(n);
  clean = 1;
  for (int trial = 0; trial < 1500; ++trial) {
    memcpy(c, d, n);
    int flips = 1 + (int)(rng() % 4);
    for (int k = 0; k < flips; ++k)
      c[rng() % n] = trial % 3 ? (char)rng() : "0123456789 -.e\n$"[rng() % 16];
    hoc_status st = hoc_msh_read_buffer(c, n, "flipped", &raw);
    if (st == HOC_OK) {
      clean &= raw_is_consistent(&raw);
      hoc_msh_raw_free(&raw);
    } else {
      clean &= st == HOC_ERR_FORMAT || st == HOC_ERR_UNSUPPORTED;
      clean &= raw.xyz == NULL && raw.n_nodes == 0;
      clean &= strlen(hoc_last_error()) > 0 && !strchr(hoc_last_error(), '\n');
    }
  }
  if (!clean) fprintf(stderr, "flipping bytes of %s: unclean result\n", path);
  CHECK(clean);
  free(c);
  free(d);
}

static hoc_status read_text(const char *text, hoc_msh_raw *raw) {
  hoc_status st = hoc_msh_read_buffer(text, strlen(text), "text", raw);
  if (st == HOC_OK) CHECK(raw_is_consistent(raw));
  return st;
}

#define HEAD41 "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
#define NODES41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n"

static void test_corrupt_inputs(void) {
  hoc_msh_raw raw;
  CHECK_STATUS(hoc_msh_read("no_such_file.msh", &raw), HOC_ERR_IO);
  CHECK(strstr(hoc_last_error(), "no_such_file.msh") != NULL);
  mkdir("a_directory.msh", 0755);
  CHECK_STATUS(hoc_msh_read("a_directory.msh", &raw), HOC_ERR_IO);
  CHECK_STATUS(hoc_msh_read_buffer("", 0, "empty", &raw), HOC_ERR_FORMAT);
  CHECK(strstr(hoc_last_error(), "not a gmsh .msh file") != NULL);
  CHECK_STATUS(hoc_msh_read_buffer(NULL, 0, "null", &raw), HOC_ERR_FORMAT);
  CHECK_STATUS(read_text(" \n\t\r\n", &raw), HOC_ERR_FORMAT);
  CHECK_STATUS(hoc_msh_read_buffer("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16, "png", &raw),
               HOC_ERR_FORMAT);
  CHECK(strstr(hoc_last_error(), "not a gmsh .msh file") != NULL);
  int clean = 1;
  for (int k = 0; k < 300; ++k) {
    char g[1024];
    size_t n = 1 + rng() % sizeof g;
    for (size_t i = 0; i < n; ++i)
      g[i] = (char)rng();
    if (k % 2)
      memcpy(g, HEAD41, n < strlen(HEAD41) ? n : strlen(HEAD41)); /* garbage after a header */
    hoc_status st = hoc_msh_read_buffer(g, n, "garbage", &raw);
    clean &= st == HOC_ERR_FORMAT || (st == HOC_OK && (hoc_msh_raw_free(&raw), 0));
  }
  CHECK(clean);
  /* a minimal valid file, then what breaks it */
  CHECK_OK(read_text(HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n", &raw));
  CHECK(raw.n_nodes == 3 && raw.n_tris == 1 && !raw.has_param[0] && raw.node_dim[2] == 2);
  hoc_msh_raw_free(&raw);
  /* CRLF, unknown sections, ignored elements (tets, points, unknown types) */
  CHECK_OK(read_text(
      "$MeshFormat\r\n4.1 0 8\r\n$EndMeshFormat\r\n$Comments\r\nhello $End\r\n$EndComments\r\n"
      "$Nodes\r\n1 4 1 4\r\n3 1 0 4\r\n1\r\n2\r\n3\r\n4\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n0 0 "
      "1\r\n$EndNodes\r\n"
      "$Elements\r\n3 3 1 3\r\n3 1 4 1\r\n1 1 2 3 4\r\n3 1 999 1\r\n2 7 7 7 7 7 7 7\r\n"
      "2 1 2 1\r\n3 1 2 3\r\n$EndElements\r\n$NodeData\r\nstuff\r\n$EndNodeData\r\n",
      &raw));
  CHECK(raw.n_nodes == 3 && raw.n_tris == 1); /* node 4 only in the tet: dropped */
  hoc_msh_raw_free(&raw);
  /* sparse tags (a sorted map), tags out of order */
  CHECK_OK(read_text(
      HEAD41
      "$Nodes\n1 3 5 9000000000\n2 1 0 3\n9000000000\n5\n700000\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n"
      "$Elements\n1 1 1 1\n2 1 2 1\n1 700000 9000000000 5\n$EndElements\n",
      &raw));
  CHECK(raw.n_nodes == 3 && raw.tri_nodes[0] == 2 && raw.tri_nodes[1] == 0 &&
        raw.tri_nodes[2] == 1);
  CHECK(raw.n_nodes == 3 && raw.node_tag[0] == 9000000000ULL);
  hoc_msh_raw_free(&raw);
  /* no triangles at all: valid, empty */
  CHECK_OK(read_text(HEAD41 NODES41 "$Elements\n0 0 0 0\n$EndElements\n", &raw));
  CHECK(raw.n_tris == 0 && raw.n_nodes == 0 && raw.order == 0);
  hoc_msh_raw_free(&raw);

  struct {
    const char *text;
    hoc_status expected;
    const char *message; /* a piece of the message, or NULL */
  } bad[] = {
      {"$MeshFormat\n", HOC_ERR_FORMAT, "$MeshFormat"},
      {"$MeshFormat\n4.1 0 8\n", HOC_ERR_FORMAT, "$EndMeshFormat"},
      {"$MeshFormat\nfour 0 8\n$EndMeshFormat\n", HOC_ERR_FORMAT, "version"},
      {"$MeshFormat\n4 0 8\n$EndMeshFormat\n", HOC_ERR_UNSUPPORTED, "4"},
      {"$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", HOC_ERR_UNSUPPORTED, NULL},
      {"$MeshFormat\n4.1 2 8\n$EndMeshFormat\n", HOC_ERR_FORMAT, "file type"},
      {"$MeshFormat\n4.1 0 7\n$EndMeshFormat\n", HOC_ERR_FORMAT, "data size"},
      {"$MeshFormat\n4.1 1 8\n\x02\x02\x02\x02\n$EndMeshFormat\n", HOC_ERR_FORMAT, "byte-order"},
      {HEAD41, HOC_ERR_FORMAT, "no $Nodes"},
      {HEAD41 NODES41, HOC_ERR_FORMAT, "no $Elements"},
      {HEAD41 "$Elements\n0 0 0 0\n$EndElements\n" NODES41, HOC_ERR_FORMAT, "before"},
      {HEAD41 "garbage\n", HOC_ERR_FORMAT, "section"},
      {HEAD41 "$Unknown\nno end\n", HOC_ERR_FORMAT, "$EndUnknown"},
      {HEAD41 "$Nodes\n1 99999999999 1 99999999999\n", HOC_ERR_FORMAT, "more than the rest"},
      {HEAD41 "$Nodes\n99999999999 1 1 1\n", HOC_ERR_FORMAT, "more than the rest"},
      {HEAD41 "$Nodes\n1 -3 1 3\n", HOC_ERR_FORMAT, "negative"},
      {HEAD41 "$Nodes\n1 99999999999999999999999 1 3\n", HOC_ERR_FORMAT, "too large"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 nan\n$EndNodes\n",
       HOC_ERR_FORMAT, "non-finite"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 inf\n$EndNodes\n",
       HOC_ERR_FORMAT, "non-finite"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 1e999\n$EndNodes\n",
       HOC_ERR_FORMAT, "non-finite"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0x\n$EndNodes\n",
       HOC_ERR_FORMAT, "not a number"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n2\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "twice"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n0\n2\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "tag 0"},
      {HEAD41 "$Nodes\n1 4 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "announced"},
      {HEAD41 "$Nodes\n1 2 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "announced"},
      {HEAD41 "$Nodes\n2 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       NULL},
      {HEAD41 "$Nodes\n1 3 1 3\n7 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "dimension"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 5 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", HOC_ERR_FORMAT,
       "parametric"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n0 0\n$EndNodes\n",
       HOC_ERR_FORMAT, "$EndNodes"},
      {HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodesX\n",
       HOC_ERR_FORMAT, "$EndNodes"},
      {HEAD41 NODES41 NODES41, HOC_ERR_FORMAT, "second"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 4\n$EndElements\n", HOC_ERR_FORMAT,
       "node 4"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2\n$EndElements\n", HOC_ERR_FORMAT, NULL},
      {HEAD41 NODES41 "$Elements\n1 2 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n", HOC_ERR_FORMAT,
       "announced"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 2 2\n1 1 2 3\n$EndElements\n", HOC_ERR_FORMAT, NULL},
      {HEAD41 NODES41 "$Elements\n1 99999999999 1 1\n", HOC_ERR_FORMAT, "more than the rest"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n1 1 2 1\n1 1 2 3\n$EndElements\n", HOC_ERR_FORMAT,
       "dimension 1"},
      {HEAD41 NODES41
       "$Elements\n2 2 1 2\n2 1 2 1\n1 1 2 3\n2 1 9 1\n2 1 2 3 1 2 3\n$EndElements\n",
       HOC_ERR_UNSUPPORTED, "orders"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 20 1\n1 1 2 3 1 2 3 1 2 3\n$EndElements\n",
       HOC_ERR_UNSUPPORTED, "incomplete"},
      {HEAD41 NODES41 "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n$Elements\n",
       HOC_ERR_FORMAT, "second"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n$EndNodes\n",
       HOC_ERR_FORMAT, NULL},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
       "$Elements\n1\n1 2 -2 0 1 1 2 3\n$EndElements\n",
       HOC_ERR_FORMAT, "tags"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
       "$Elements\n2\n1 2 2 0 1 1 2 3\n2 9 2 0 1 1 2 3 1 2 3\n$EndElements\n",
       HOC_ERR_UNSUPPORTED, "orders"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
       "$Elements\n1\n1 2 2 0 1 1 2 7\n$EndElements\n",
       HOC_ERR_FORMAT, "node 7"},
      {"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
       "$Elements\n2\n1 2 2 0 1 1 2 3\n$EndElements\n",
       HOC_ERR_FORMAT, NULL},
  };
  int all = 1;
  for (size_t k = 0; k < sizeof bad / sizeof *bad; ++k) {
    hoc_status st = read_text(bad[k].text, &raw);
    int ok = st == bad[k].expected && (!bad[k].message || strstr(hoc_last_error(), bad[k].message));
    ok &= raw.n_nodes == 0 && raw.xyz == NULL;
    if (!ok)
      fprintf(stderr, "bad input %zu: got %s (%s)\n", k, hoc_status_string(st), hoc_last_error());
    if (st == HOC_OK) hoc_msh_raw_free(&raw);
    all &= ok;
  }
  CHECK(all);
  /* messages name the place */
  read_text(HEAD41 "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 nan\n$EndNodes\n", &raw);
  CHECK(strstr(hoc_last_error(), "'text' line 12 ($Nodes)") != NULL);

  /* MSH 2.2: classification by the lowest-dimensional element using a node */
  CHECK_OK(read_text(
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"a $b\"\n$EndPhysicalNames\n"
      "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 5 5 5\n$EndNodes\n"
      "$Elements\n5\n1 15 2 0 7 1\n2 1 2 0 4 1 2\n3 2 2 0 6 1 2 3\n4 2 2 0 5 2 3 1\n5 8 2 0 4 1 2 "
      "4\n$EndElements\n",
      &raw));
  int ok = raw.n_nodes == 3 && raw.n_tris == 2 && raw.n_lines == 1;
  ok = ok && raw.node_dim[0] == 0 && raw.node_entity_tag[0] == 7; /* a point */
  ok = ok && raw.node_dim[1] == 1 && raw.node_entity_tag[1] == 4; /* on the line */
  ok = ok && raw.node_dim[2] == 2 && raw.node_entity_tag[2] == 5; /* lowest surface tag */
  ok = ok && raw.tri_surface_tag[0] == 6 && raw.tri_surface_tag[1] == 5;
  CHECK(ok);
  hoc_msh_raw_free(&raw);
}

int main(void) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  test_numbers();
  test_lattice_is_gmsh();
  const int orders[] = {1, 2, 3, 5, 10};
  for (size_t k = 0; k < sizeof orders / sizeof *orders; ++k)
    test_round_trip(orders[k]);
  test_special_values();
  test_write_arguments();
  test_gmsh_written();
  gmshFinalize(&ierr);
  test_corpus();
  test_binary_variants();
  test_binary22();
  test_corrupt_inputs();
  test_corrupt_file("synth_p3_41_param.msh");
  test_corrupt_file("synth_p3_22.msh");
  test_corrupt_file("gmsh41.msh");
  test_corrupt_file("gmsh41bin.msh");
  test_corrupt_file("gmsh22.msh");
  test_corrupt_file("gmsh22param.msh");
  test_corrupt_file("gmsh22bin.msh");
  test_corrupt_file("gmsh22parambin.msh");
  test_corrupt_file("synth_p3_22bin_param.msh");
  test_corrupt_file("synth_p3_41bin.msh");
  return test_report();
}
