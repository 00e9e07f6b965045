/* Numbers of the gmsh MSH formats, shared by the writer and the reader:
 * the element type tables, powers of ten as 128-bit mantissas, the exact
 * decimal output of a double (printf "%.17g" semantics) and its exact
 * input (strtod semantics).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "io/msh_digits.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Element types ------------------------------------------------------------ */

int hoc_msh_triangle_type(int p) {
  static const int types[11] = {0, 2, 9, 21, 23, 25, 42, 43, 44, 45, 46};
  return p >= 1 && p <= 10 ? types[p] : 0;
}

int hoc_msh_line_type(int p) {
  static const int types[11] = {0, 1, 8, 26, 27, 28, 62, 63, 64, 65, 66};
  return p >= 1 && p <= 10 ? types[p] : 0;
}

int hoc_msh_element_nodes(int type) {
  /* gmshModelMeshGetElementProperties of every type gmsh 4.8 knows (0: it
   * does not know the type, or the element has a variable size) */
  /* clang-format off */
  static const short nodes[138] = {
      0,   2,   3,   4,   4,   8,   6,   5,   3,   6,   /* 0-9 */
      9,   10,  27,  18,  14,  1,   8,   20,  15,  13,  /* 10-19 */
      9,   10,  12,  15,  15,  21,  4,   5,   6,   20,  /* 20-29 */
      35,  56,  22,  28,  0,   0,   16,  25,  36,  12,  /* 30-39 */
      16,  20,  28,  36,  45,  55,  66,  49,  64,  81,  /* 40-49 */
      100, 121, 18,  21,  24,  27,  30,  24,  28,  32,  /* 50-59 */
      36,  40,  7,   8,   9,   10,  11,  0,   0,   0,   /* 60-69 */
      0,   84,  120, 165, 220, 286, 0,   0,   0,   34,  /* 70-79 */
      40,  46,  52,  58,  1,   1,   1,   1,   1,   1,   /* 80-89 */
      0,   0,   64,  125, 216, 343, 512, 729, 1000, 32, /* 90-99 */
      44,  56,  68,  80,  92,  104, 0,   0,   0,   0,   /* 100-109 */
      0,   0,   0,   0,   0,   0,   0,   0,   30,  55,  /* 110-119 */
      91,  140, 204, 285, 385, 21,  29,  37,  45,  53,  /* 120-129 */
      61,  69,  1,   0,   0,   0,   0,   16};           /* 130-137 */
  /* clang-format on */
  return type >= 0 && type < (int)(sizeof nodes / sizeof *nodes) ? nodes[type] : 0;
}

int hoc_msh_triangle_order(int type) {
  for (int p = 1; p <= 10; ++p)
    if (hoc_msh_triangle_type(p) == type) return p;
  /* incomplete triangles: 9, 12, 15 nodes (orders 3-5), 18..30 (orders 6-10) */
  switch (type) {
  case 20: return -3;
  case 22: return -4;
  case 24: return -5;
  default: return type >= 52 && type <= 56 ? -(type - 46) : 0;
  }
}

int hoc_msh_line_order(int type) {
  for (int p = 1; p <= 10; ++p)
    if (hoc_msh_line_type(p) == type) return p;
  return 0;
}

/* Powers of ten as 128-bit mantissas --------------------------------------- */

enum { POW10_MIN = -350, POW10_MAX = 350, BIG_LIMBS = 48, NEG_SHIFT = 1400 };

typedef struct pow10_entry {
  uint64_t hi, lo;
  int b;
} pow10_entry;

static pow10_entry pow10_table[POW10_MAX - POW10_MIN + 1];
static pthread_once_t pow10_once = PTHREAD_ONCE_INIT;

/* Little-endian 32-bit limbs of a nonnegative integer. */
typedef struct big {
  uint32_t limb[BIG_LIMBS];
  int n;
} big;

static int big_bitlen(const big *x) {
  int n = x->n;
  while (n > 0 && !x->limb[n - 1])
    --n;
  if (!n) return 0;
  int bits = 32 * (n - 1);
  for (uint32_t top = x->limb[n - 1]; top; top >>= 1)
    ++bits;
  return bits;
}

static int big_bit(const big *x, int i) {
  return i >= 0 && i / 32 < x->n ? (int)((x->limb[i / 32] >> (i % 32)) & 1u) : 0;
}

/* The 128 bits of x from bit `bitlen-1` down (zeros below bit 0). */
static void big_top128(const big *x, int bitlen, pow10_entry *e) {
  uint64_t hi = 0, lo = 0;
  for (int i = bitlen - 1; i >= bitlen - 128; --i) {
    hi = (hi << 1) | (lo >> 63);
    lo = (lo << 1) | (uint64_t)big_bit(x, i);
  }
  e->hi = hi;
  e->lo = lo;
}

static void build_pow10_table(void) {
  /* q >= 0: the exact integer 10^q, truncated to its top 128 bits */
  big x = {{1}, 1};
  for (int q = 0; q <= POW10_MAX; ++q) {
    if (q > 0) {
      uint64_t carry = 0;
      for (int k = 0; k < x.n; ++k) {
        uint64_t t = (uint64_t)x.limb[k] * 10u + carry;
        x.limb[k] = (uint32_t)t;
        carry = t >> 32;
      }
      if (carry) x.limb[x.n++] = (uint32_t)carry;
    }
    int bits = big_bitlen(&x);
    pow10_entry *e = &pow10_table[q - POW10_MIN];
    big_top128(&x, bits, e);
    e->b = bits - 128;
  }
  /* q < 0: floor(2^NEG_SHIFT / 10^-q) (repeated floor division by 10 is
   * floor division by 10^-q), truncated to its top 128 bits */
  memset(&x, 0, sizeof x);
  x.n = NEG_SHIFT / 32 + 1;
  x.limb[NEG_SHIFT / 32] = 1u << (NEG_SHIFT % 32);
  for (int q = -1; q >= POW10_MIN; --q) {
    uint64_t rem = 0;
    for (int k = x.n - 1; k >= 0; --k) {
      uint64_t t = (rem << 32) | x.limb[k];
      x.limb[k] = (uint32_t)(t / 10u);
      rem = t % 10u;
    }
    int bits = big_bitlen(&x);
    pow10_entry *e = &pow10_table[q - POW10_MIN];
    big_top128(&x, bits, e);
    e->b = bits - 128 - NEG_SHIFT;
  }
}

int hoc_io_pow10(int q, uint64_t *hi, uint64_t *lo, int *b) {
  if (q < POW10_MIN || q > POW10_MAX) return 0;
  pthread_once(&pow10_once, build_pow10_table);
  const pow10_entry *e = &pow10_table[q - POW10_MIN];
  *hi = e->hi;
  *lo = e->lo;
  *b = e->b;
  return 1;
}

/* Exact "%.17g" ----------------------------------------------------------- */

/* floor(e * log10(2)) (first guess; the caller corrects it). */
static int floor_log10_pow2(int e) {
  long t = (long)e * 78913L;
  return (int)(t >= 0 ? t / 262144L : -((-t + 262143L) / 262144L));
}

#if defined(__SIZEOF_INT128__)
__extension__ typedef unsigned __int128 u128;

/* The 17 significant digits of v > 0 (finite), correctly rounded to
 * nearest; *exp10 is the decimal exponent of the first digit. Returns 0 when
 * v * 10^q is too close to a rounding tie to decide in 128-bit precision
 * (the caller then asks printf). */
static int digits17(double v, uint64_t *digits, int *exp10) {
  uint64_t bits;
  memcpy(&bits, &v, sizeof bits);
  uint64_t frac = bits & ((UINT64_C(1) << 52) - 1);
  int be = (int)((bits >> 52) & 0x7ff);
  uint64_t m = be ? frac | (UINT64_C(1) << 52) : frac; /* v = m 2^e */
  int e = be ? be - 1075 : -1074;
  int msb = 63;
  while (!(m >> msb))
    --msb;
  int d = floor_log10_pow2(e + msb); /* first guess of floor(log10 v) */
  const uint64_t lo17 = UINT64_C(10000000000000000), hi17 = UINT64_C(100000000000000000);
  for (int iter = 0; iter < 3; ++iter) {
    uint64_t ph, pl;
    int pb;
    if (!hoc_io_pow10(16 - d, &ph, &pl, &pb)) return 0;
    /* m * 10^q as 192 bits (w2 w1 w0), times 2^(e + pb) */
    u128 p0 = (u128)m * pl, p1 = (u128)m * ph;
    uint64_t w0 = (uint64_t)p0;
    u128 mid = (p0 >> 64) + (uint64_t)p1;
    uint64_t w1 = (uint64_t)mid;
    uint64_t w2 = (uint64_t)(p1 >> 64) + (uint64_t)(mid >> 64);
    /* X = v 10^q 2^64 = product >> s, with 3 <= s <= 64 */
    int s = -(e + pb + 64);
    if (s < 1 || s > 64) return 0;
    u128 top = ((u128)w2 << 64) | w1;
    u128 x = s == 64 ? top : (top << (64 - s)) | (w0 >> s);
    uint64_t ip = (uint64_t)(x >> 64), fp = (uint64_t)x;
    if (ip < lo17) {
      --d;
      continue;
    }
    if (ip >= hi17) {
      ++d;
      continue;
    }
    /* x is below the true value by less than 2 units of 2^-64 */
    const uint64_t half = UINT64_C(1) << 63;
    if (fp >= half - 16 && fp <= half + 16) return 0;
    uint64_t n = ip + (fp > half);
    if (n == hi17) {
      n = lo17;
      ++d;
    }
    *digits = n;
    *exp10 = d;
    return 1;
  }
  return 0;
}
#else
static int digits17(double v, uint64_t *digits, int *exp10) {
  (void)v, (void)digits, (void)exp10;
  return 0;
}
#endif

size_t hoc_io_format_double(double v, char *out) {
  if (!isfinite(v) || v == 0) {
    if (v == 0) {
      size_t n = 0;
      if (signbit(v)) out[n++] = '-';
      out[n++] = '0';
      out[n] = '\0';
      return n;
    }
    return (size_t)snprintf(out, 32, "%.17g", v);
  }
  uint64_t n;
  int d;
  if (!digits17(fabs(v), &n, &d)) return (size_t)snprintf(out, 32, "%.17g", v);
  char dig[17];
  for (int k = 16; k >= 0; --k) {
    dig[k] = (char)('0' + n % 10);
    n /= 10;
  }
  int nd = 17; /* significant digits after dropping trailing zeros */
  while (nd > 1 && dig[nd - 1] == '0')
    --nd;
  char *s = out;
  if (v < 0) *s++ = '-';
  if (d < -4 || d >= 17) { /* d.ddde+XX */
    *s++ = dig[0];
    if (nd > 1) {
      *s++ = '.';
      memcpy(s, dig + 1, (size_t)(nd - 1));
      s += nd - 1;
    }
    *s++ = 'e';
    *s++ = d < 0 ? '-' : '+';
    int a = d < 0 ? -d : d;
    if (a < 10) *s++ = '0';
    s += format_u64((uint64_t)a, s);
  } else if (d >= 0) { /* ddd.ddd */
    memcpy(s, dig, (size_t)d + 1);
    s += d + 1;
    if (nd > d + 1) {
      *s++ = '.';
      memcpy(s, dig + d + 1, (size_t)(nd - d - 1));
      s += nd - d - 1;
    }
  } else { /* 0.000ddd */
    *s++ = '0';
    *s++ = '.';
    for (int k = 0; k < -d - 1; ++k)
      *s++ = '0';
    memcpy(s, dig, (size_t)nd);
    s += nd;
  }
  *s = '\0';
  return (size_t)(s - out);
}

/* Decimal numbers -------------------------------------------------------------- */

/* strtod on a copy with a NUL (the buffer the reader scans has none). */
static int parse_double_slow(const char *s, size_t n, double *v) {
  char buf[512];
  if (n == 0 || n >= sizeof buf) return 0;
  memcpy(buf, s, n);
  buf[n] = '\0';
  char *end;
  *v = strtod(buf, &end);
  return end == buf + n;
}

int hoc_io_parse_double(const char *s, size_t n, double *v) {
#if defined(__SIZEOF_INT128__)
  if (n > 400) return parse_double_slow(s, n, v); /* bounds the digit counters below */
  const char *p = s, *end = s + n;
  int neg = 0;
  if (p < end && (*p == '-' || *p == '+')) neg = *p++ == '-';
  uint64_t w = 0;    /* the first 19 significant digits */
  int nd = 0;        /* digits in w */
  int scale = 0;     /* value = w 10^(scale + exponent) */
  int truncated = 0; /* nonzero digits beyond the 19th */
  int digits = 0;    /* digits seen at all */
  for (; p < end && *p >= '0' && *p <= '9'; ++p, ++digits) {
    if (nd < 19) {
      w = 10 * w + (uint64_t)(*p - '0');
      nd += w != 0;
    } else {
      ++scale;
      truncated |= *p != '0';
    }
  }
  if (p < end && *p == '.') {
    for (++p; p < end && *p >= '0' && *p <= '9'; ++p, ++digits) {
      if (nd < 19) {
        w = 10 * w + (uint64_t)(*p - '0');
        nd += w != 0;
        --scale;
      } else {
        truncated |= *p != '0';
      }
    }
  }
  if (!digits) return parse_double_slow(s, n, v); /* inf, nan or not a number */
  if (p < end && (*p == 'e' || *p == 'E')) {
    ++p;
    int eneg = 0, edigits = 0, e = 0;
    if (p < end && (*p == '-' || *p == '+')) eneg = *p++ == '-';
    for (; p < end && *p >= '0' && *p <= '9'; ++p, ++edigits)
      if (e < 100000) e = 10 * e + (*p - '0');
    if (!edigits) return 0;
    scale += eneg ? -e : e;
  }
  if (p != end) return 0;
  if (w == 0 && !truncated) {
    *v = neg ? -0.0 : 0.0;
    return 1;
  }
  uint64_t ph, pl;
  int pb;
  if (truncated || !hoc_io_pow10(scale, &ph, &pl, &pb)) return parse_double_slow(s, n, v);
  /* w 10^scale ~= P 2^(pb - lz) with P = (w << lz) M, 2^190 <= P < 2^192;
   * P is below the exact product by less than 2^64 */
  int lz = 0;
  while (!(w >> (63 - lz)))
    ++lz;
  uint64_t wn = w << lz;
  u128 p0 = (u128)wn * pl, p1 = (u128)wn * ph;
  u128 mid = (p0 >> 64) + (uint64_t)p1;
  uint64_t w1 = (uint64_t)mid;
  uint64_t w2 = (uint64_t)(p1 >> 64) + (uint64_t)(mid >> 64);
  int shift = (w2 >> 63) ? 139 : 138; /* the 53-bit mantissa is P >> shift */
  uint64_t m = w2 >> (shift - 128);
  int hb = (int)((w2 >> (shift - 129)) & 1);          /* the bit worth half an ulp */
  uint64_t mask = (UINT64_C(1) << (shift - 129)) - 1; /* the bits of w2 below it */
  if (hb == 0 && (w2 & mask) == mask && w1 == UINT64_MAX) return parse_double_slow(s, n, v);
  if (hb == 1 && (w2 & mask) == 0 && w1 == 0) return parse_double_slow(s, n, v);
  m += (uint64_t)hb;
  int e2 = shift + pb - lz; /* value = m 2^e2 */
  if (m == UINT64_C(1) << 53) {
    m >>= 1;
    ++e2;
  }
  int biased = e2 + 1075;
  if (biased < 1 || biased > 2046) return parse_double_slow(s, n, v); /* subnormal or overflow */
  uint64_t bits = ((uint64_t)biased << 52) | (m & ((UINT64_C(1) << 52) - 1));
  if (neg) bits |= UINT64_C(1) << 63;
  memcpy(v, &bits, sizeof bits);
  return 1;
#else
  return parse_double_slow(s, n, v);
#endif
}
