/* Shades one pixel with the clothbake C interface (capi/clothbake.h, docs/integration.md):
 * opens an asset from memory, estimates the cloth BSDF over one pixel's footprint for a light and
 * a view, and samples one light direction with its density.
 *   shade_pixel ASSET.cbk
 * prints "value R G B" and "sample WX WY WZ PDF" (%.17g). */
#include <stdio.h>
#include <stdlib.h>

#include "clothbake.h"

static void* read_file(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  void* bytes = n > 0 ? malloc((size_t)n) : NULL;
  if (bytes && fread(bytes, 1, (size_t)n, f) != (size_t)n) {
    free(bytes);
    bytes = NULL;
  }
  fclose(f);
  *size = (size_t)n;
  return bytes;
}

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: shade_pixel ASSET.cbk\n");
    return 1;
  }
  size_t size = 0;
  void* bytes = read_file(argv[1], &size);
  if (!bytes) {
    fprintf(stderr, "%s: cannot read\n", argv[1]);
    return 2;
  }
  cb_error error;
  cb_asset* asset = NULL;
  if (cb_asset_open_memory(bytes, size, 0, NULL, &asset, &error) != CB_OK) {
    fprintf(stderr, "%s\n", error.message);
    return 3;
  }
  free(bytes); /* the asset holds its own copy */
  cb_options options;
  cb_options_default(&options); /* unbiased multi-scale, 1 sample per estimate */
  cb_evaluator* evaluator = NULL;
  if (cb_evaluator_create(asset, &options, NULL, &evaluator, &error) != CB_OK) {
    fprintf(stderr, "%s\n", error.message);
    cb_asset_close(asset);
    return 3;
  }
  /* A pixel that covers half a tile by a quarter (tile units), lit from above-left. */
  const cb_footprint pixel = {0.125, 0.25, 0.625, 0.5};
  const double wi[3] = {-0.3, 0.2, 0.9}, wo[3] = {0.1, -0.2, 1.0}, u[3] = {0.3, 0.6, 0.2};
  cb_rng rng;
  cb_rng_seed(&rng, 1);
  double rgb[3];
  cb_direction_sample sample;
  int code = 0;
  if (cb_estimate(evaluator, &pixel, wi, wo, CB_LOBES_ALL, &rng, rgb, &error) != CB_OK ||
      cb_sample_direction(evaluator, &pixel, wo, u, &sample, &error) != CB_OK) {
    fprintf(stderr, "%s\n", error.message);
    code = 4;
  } else {
    printf("value %.17g %.17g %.17g\n", rgb[0], rgb[1], rgb[2]);
    printf("sample %.17g %.17g %.17g %.17g\n", sample.wi[0], sample.wi[1], sample.wi[2],
           sample.pdf);
  }
  cb_evaluator_destroy(evaluator);
  cb_asset_close(asset);
  return code;
}
