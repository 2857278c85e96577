/* clothbake.h: the C interface of the clothbake reader and evaluator (docs/integration.md).
 *
 * What a renderer needs to shade a clothbake asset: open an asset (from memory or a file), create
 * an evaluator over it, and per shading point estimate the cloth BSDF averaged over the pixel's
 * footprint for a light/view pair (Eq. 5 of Zhu et al. 2024, already multiplied by |cos| of the
 * light), sample a light direction with its density, and evaluate that density.
 *
 * Conventions, for every function:
 *  - C99 and C++17; no exception crosses this interface; every function that can fail returns a
 *    cb_result and, when `error` is not NULL, writes a NUL-terminated message naming the asset,
 *    the section or the argument into the caller's cb_error (no global or thread-local state:
 *    the messages are as thread-safe as the caller's buffers).
 *  - Directions are in the cloth's local shading frame: z along the surface normal, x along the
 *    tile's u axis (the warp's tangent direction of the weave), y along v. `wi` points towards the
 *    light, `wo` towards the viewer; any finite non-zero vectors (normalised here).
 *  - Footprints are axis-aligned rectangles in tile units: one unit is one repeat of the fabric's
 *    tile along u or v (a renderer with texture coordinates uv and `tiles_per_uv` repeats per uv
 *    unit passes u * tiles_per_uv). Any position with corners within 2^40 texels of the origin
 *    (the tile wraps) and any size up to 2^24 tiles; a zero-area footprint is a point.
 *  - Random numbers: a cb_rng the caller owns (one per thread); the same seed gives the same
 *    estimates on every platform (SplitMix64).
 *  - Untrusted bytes: cb_asset_open_* validates the whole asset unless CB_OPEN_TRUSTED is given
 *    (then only the structure is checked and the views check what they read; see its comment).
 */
#ifndef CLOTHBAKE_H
#define CLOTHBAKE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#define CB_NOEXCEPT noexcept
#else
#define CB_NOEXCEPT
#endif

#define CLOTHBAKE_C_API_VERSION 1

typedef enum cb_result {
  CB_OK = 0,
  CB_ERROR_INVALID_ARGUMENT = 1, /* a NULL pointer, a bad footprint, direction, option or count */
  CB_ERROR_IO = 2,               /* the file cannot be opened, sized or mapped */
  CB_ERROR_INVALID_ASSET = 3,    /* not an asset, another major version, truncated, corrupt or
                                    failing validation: the message names the check (CBK-Ennn) */
  CB_ERROR_NOT_FOUND = 4,        /* the asset lacks what the evaluator or the method needs */
  CB_ERROR_UNSUPPORTED = 5,      /* valid, but not readable here (codec, section version, a
                                    method or table form the single file leaves out), or the
                                    allocator returned NULL for a decoded or derived table */
  CB_ERROR_OUT_OF_MEMORY = 6,    /* the caller's allocator returned NULL */
  CB_ERROR_OUT_OF_PLAN = 7       /* a scene-planned asset left out what the query needs: estimate
                                    it with CB_METHOD_BRUTE, which reads no tables, or return 0 */
} cb_result;

/* The name of a result ("CB_OK", "CB_ERROR_IO", ...); never NULL. Pure. */
const char* cb_result_name(cb_result result) CB_NOEXCEPT;

/* A message for the caller's buffer: always NUL-terminated, truncated to fit. */
typedef struct cb_error {
  char message[256];
} cb_error;

/* Memory. `allocate` returns `size` bytes aligned to `alignment` (a power of two, at most 64) or
 * NULL; `release` frees what it returned (never called with NULL). Every byte the library holds
 * comes from it: the objects (cb_asset, cb_evaluator), the copy of an asset's bytes, the decoded
 * maps and tables (the asset's allocator) and the evaluator's derived sums, some built on first
 * use by cb_estimate (the evaluator's allocator; docs/integration.md, "Memory"). Both may be called
 * from any thread that calls into the object they serve, so they must be thread-safe. NULL, or a
 * struct with a NULL function, selects aligned_alloc/free. */
typedef struct cb_allocator {
  void* (*allocate)(void* user, size_t size, size_t alignment);
  void (*release)(void* user, void* pointer);
  void* user;
} cb_allocator;

typedef struct cb_asset cb_asset;
typedef struct cb_evaluator cb_evaluator;

/* Open flags. */
#define CB_OPEN_BORROW                                                      \
  1u /* open_memory: read the caller's bytes in place (they must stay alive \
        and unchanged until cb_asset_close, and start at an 8-byte          \
        boundary); without it the bytes are copied */
#define CB_OPEN_TRUSTED                                                      \
  2u /* skip the full validation (every checksum, every value range, every   \
        baked view opened and cross-checked, what `clothbake validate`       \
        does): open then checks the structure only (magic, version, the      \
        section table, sizes and offsets), and the evaluator the layouts and \
        shapes of the views it opens and some values, but no checksum and    \
        not every value: damaged bytes may shade as wrong values. For assets \
        the caller baked or verified (docs/integration.md) */

/* Opens an asset from `size` bytes at `bytes`. Validates it (see CB_OPEN_TRUSTED): the cost is one
 * pass over the bytes and opening every baked table (docs/performance.md, "C interface"). Without
 * CB_OPEN_BORROW the bytes are copied into memory from `allocator` (NULL: malloc), so the caller's
 * buffer may be freed after the call. On success *out is an asset to close with cb_asset_close; on
 * failure *out is NULL. Errors: INVALID_ARGUMENT (NULL bytes or out, unknown flags, a borrowed
 * buffer not 8-byte aligned), INVALID_ASSET (the message names the first failed check),
 * UNSUPPORTED, OUT_OF_MEMORY. Safe on untrusted bytes. Thread-safe. */
cb_result cb_asset_open_memory(const void* bytes, size_t size, uint32_t flags,
                               const cb_allocator* allocator, cb_asset** out,
                               cb_error* error) CB_NOEXCEPT;

/* Opens the asset file at `path` (mapped read-only, not copied; the file must not be truncated
 * while open). Validation, errors and thread safety as cb_asset_open_memory, plus IO. */
cb_result cb_asset_open_file(const char* path, uint32_t flags, const cb_allocator* allocator,
                             cb_asset** out, cb_error* error) CB_NOEXCEPT;

/* Closes an asset (NULL: nothing). Every evaluator over it must be destroyed first. */
void cb_asset_close(cb_asset* asset) CB_NOEXCEPT;

/* What a renderer may want to know of an asset. */
typedef struct cb_asset_info {
  uint32_t resolution; /* texels per tile side (tiles are square) */
  double tile_size_mm; /* the tile's physical side, in millimetres (0: unknown) */
  uint32_t
      scene_planned; /* 1 when a scene plan left parts out (queries may be CB_ERROR_OUT_OF_PLAN) */
} cb_asset_info;

/* Fills *out (zeroed on error). Errors: INVALID_ARGUMENT (NULL); NOT_FOUND or INVALID_ASSET when
 * the fabric record or the scene-plan record of an asset opened trusted is missing or damaged.
 * Thread-safe. */
cb_result cb_asset_get_info(const cb_asset* asset, cb_asset_info* out, cb_error* error) CB_NOEXCEPT;

/* Methods (docs/evaluator.md, "Methods"). */
typedef enum cb_method {
  CB_METHOD_MULTISCALE = 0,       /* unbiased multi-scale (the default) */
  CB_METHOD_MULTISCALE_PAPER = 1, /* the paper's Eq. 8-10 as printed (biased); not in the single
                                     source file clothbake.cpp: UNSUPPORTED there */
  CB_METHOD_BRUTE = 2,            /* Monte Carlo over the footprint, no tables */
  CB_METHOD_REFERENCE = 3         /* the exact integral (slow on wide footprints) */
} cb_method;

/* Lobes (Eq. 4), to restrict an estimate to; CB_LOBES_ALL for the whole BSDF. */
#define CB_LOBE_SPECULAR_REFLECTION 1u
#define CB_LOBE_SPECULAR_TRANSMISSION 2u
#define CB_LOBE_DIFFUSE_REFLECTION 4u
#define CB_LOBE_DIFFUSE_TRANSMISSION 8u
#define CB_LOBE_DELTA_TRANSMISSION 16u
#define CB_LOBE_SHEEN 32u
#define CB_LOBES_ALL 63u

/* Evaluator options: a POD struct; fill it with cb_options_default first. */
typedef struct cb_options {
  uint32_t method;        /* cb_method, default CB_METHOD_MULTISCALE */
  uint32_t tables;        /* 0 = auto (compressed, else raw), 1 = raw, 2 = compressed; the
                             single source file reads compressed tables only (1: UNSUPPORTED) */
  uint32_t sheen;         /* 0 = the published sheen table (default), 1 = converged albedo */
  uint32_t spp;           /* samples per estimate for the sampling methods, default 1 (>= 1) */
  double direct_max_side; /* the multi-scale methods sum footprints below this many texels a
                             side exactly, default 1 */
} cb_options;

/* The defaults above. Pure. */
void cb_options_default(cb_options* options) CB_NOEXCEPT;

/* Creates an evaluator over `asset` (which must outlive it): opens the views every method needs and
 * builds the derived footprint sums (docs/evaluator.md, "Footprint sums": a few MB for a 256^2
 * tile). Errors: INVALID_ARGUMENT (NULL, an option out of range), NOT_FOUND (a section the
 * evaluator needs; the multi-scale methods also need the Integral-Radiance tables), INVALID_ASSET
 * (sections that disagree), OUT_OF_MEMORY (the allocator), UNSUPPORTED (the derived sums could not
 * be allocated). Thread-safe. */
cb_result cb_evaluator_create(const cb_asset* asset, const cb_options* options,
                              const cb_allocator* allocator, cb_evaluator** out,
                              cb_error* error) CB_NOEXCEPT;

/* Destroys an evaluator (NULL: nothing). */
void cb_evaluator_destroy(cb_evaluator* evaluator) CB_NOEXCEPT;

/* A footprint in tile units: [u0, u1] x [v0, v1], u1 >= u0, v1 >= v0. */
typedef struct cb_footprint {
  double u0, v0, u1, v1;
} cb_footprint;

/* The caller's random state, one per thread: cb_rng_seed it once. */
typedef struct cb_rng {
  uint64_t state;
} cb_rng;

/* Seeds a random state (any seed). Pure. */
void cb_rng_seed(cb_rng* rng, uint64_t seed) CB_NOEXCEPT;

/* One estimate of the footprint average of the BSDF times |cos| of wi, the visibility and the
 * parallax included (Eq. 5), over the lobes of `lobes` (a non-zero subset of CB_LOBES_ALL), in RGB:
 * finite; >= 0 for BRUTE and REFERENCE, while one estimate of the control-variate methods can be
 * slightly negative (not clamped: clamping would bias the mean). The method and spp are the
 * evaluator's options; the sampling methods advance `rng`; the estimates of MULTISCALE and BRUTE
 * are unbiased (average several for less noise), MULTISCALE_PAPER's are biased by design.
 * Errors: INVALID_ARGUMENT (NULL, a bad footprint, direction or lobe mask), NOT_FOUND (tables the
 * method needs), OUT_OF_PLAN, UNSUPPORTED (an allocation below failed), INVALID_ASSET (values
 * that overflow the evaluator's sums: the estimate is refused, never returned non-finite). On
 * error out_rgb is 0. Thread-safe: one evaluator may serve every thread, each with its own rng.
 * Allocates on a view bin's or a parallax direction's first use, and per estimate for tables of
 * more than 1 024 images or for REFERENCE on wide footprints (docs/integration.md). */
cb_result cb_estimate(const cb_evaluator* evaluator, const cb_footprint* footprint,
                      const double wi[3], const double wo[3], uint32_t lobes, cb_rng* rng,
                      double out_rgb[3], cb_error* error) CB_NOEXCEPT;

/* A sampled light direction. */
typedef struct cb_direction_sample {
  uint32_t valid;    /* 0 when the BSDF is 0 for wo (no sample) */
  uint32_t is_delta; /* 1: the delta transmission lobe, wi = -wo, pdf its discrete probability */
  double wi[3];      /* unit, local frame */
  double pdf;        /* solid-angle density of the continuous techniques at wi (or P(delta)) */
} cb_direction_sample;

/* Samples wi for the view wo from the lobe mixture at the footprint's representative texel (its
 * centre shifted by the mean parallax offset; docs/evaluator.md, "Importance sampling"), for a
 * footprint with area mixed 3:1 with that texel's half in a gap, so that every lobe the footprint
 * covers can be drawn. u[0..2] uniform in [0, 1). cb_estimate's value at wi divided by pdf is
 * an unbiased estimate. Errors: INVALID_ARGUMENT (NULLs, a bad footprint or wo, any u outside [0, 1) or NaN),
 * OUT_OF_PLAN, UNSUPPORTED (see the allocation). Thread-safe.
 * Allocates on a parallax direction's first use in an entropy-coded parallax table (the default
 * bake's): its decoded plane and SAT, kept for later calls; UNSUPPORTED when that fails. */
cb_result cb_sample_direction(const cb_evaluator* evaluator, const cb_footprint* footprint,
                              const double wo[3], const double u[3], cb_direction_sample* out,
                              cb_error* error) CB_NOEXCEPT;

/* The density cb_sample_direction's continuous techniques give wi (it integrates to
 * 1 - P(delta)), for multiple importance sampling. Errors, allocation and thread safety as
 * cb_sample_direction. */
cb_result cb_direction_pdf(const cb_evaluator* evaluator, const cb_footprint* footprint,
                           const double wi[3], const double wo[3], double* out_pdf,
                           cb_error* error) CB_NOEXCEPT;

#ifdef __cplusplus
}
#endif

#undef CB_NOEXCEPT

#endif /* CLOTHBAKE_H */
