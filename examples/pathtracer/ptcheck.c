/* ptcheck: statistical checks on the path tracer's EXR output (the end-to-end tests).
 *
 *   ptcheck finite  IMG.exr...            no NaN or Inf in any channel of any image
 *   ptcheck furnace IMG.exr --range R     every pixel's expectation is 1 (white furnace)
 *   ptcheck energy  IMG.exr               a furnace image of a lossy material: <= 1
 *   ptcheck agree   A.exr B.exr...        the images estimate the same thing
 *   ptcheck same    A.exr B.exr           the images are identical, value for value, in
 *                   their shared channels (with --rel R --abs A: within A + R |value|)
 *
 * Every mode first runs `finite` on its images. Exit status 0 = pass, 1 = fail, 2 = usage.
 *
 * furnace: P pixels of N samples each, every sample an independent estimate in [0, R]
 * with expectation 1 (R is the integrator's bound for the scene, given by the caller; the
 * test's CMakeLists derives it). Hoeffding: P(|mean - 1| >= t) <= 2 exp(-2 N t^2 / R^2),
 * so with a union bound over the P x 3 pixel channels, every pixel is within
 *   t = R sqrt(ln(6 P / delta) / (2 N))
 * of 1 except with probability delta (1e-6). Rigorous, and loose: it catches a wrong
 * weight, not a small bias; the image mean (P N samples) must also be within --tol (1%).
 *
 * energy: needs the --aovs channels. Over the pixels whose every camera sample hit the
 * sphere (coverage 1), the mean of each channel must be <= 1 + k SE, SE = sqrt(sum of the
 * pixels' variance.X) / count (the standard error of that mean; k = --sigmas, 4).
 *
 * agree: needs the --aovs channels and independent images (different seeds). For each
 * channel, the image means, and the means of --blocks x --blocks regions, of every image
 * against the first: |m_a - m_b| <= z sqrt(SE_a^2 + SE_b^2), z from the normal quantile
 * for a family-wise false alarm rate of --alpha (1e-4) over all comparisons (Bonferroni).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "image_io.h"

static int load(const char *path, image *img)
{
    char err[512];
    if (image_read(path, img, err, sizeof err) != 0) {
        fprintf(stderr, "ptcheck: %s\n", err);
        return -1;
    }
    return 0;
}

/* No NaN or Inf anywhere, and the renderer saw no non-finite sample. */
static int check_finite(const char *path, const image *img)
{
    const size_t n = (size_t)img->width * (size_t)img->height * (size_t)img->channels;
    size_t i, bad = 0;
    const char *nf = image_attr_value(img, "glint:nonfinite_samples");
    for (i = 0; i < n; i++)
        if (!isfinite(img->pixels[i]))
            bad++;
    if (bad) {
        printf("FAIL %s: %zu non-finite values\n", path, bad);
        return 0;
    }
    if (nf && strcmp(nf, "0") != 0) {
        printf("FAIL %s: the renderer counted %s non-finite samples\n", path, nf);
        return 0;
    }
    printf("ok   %s: %dx%d, %d channels, all finite\n", path, img->width, img->height,
           img->channels);
    return 1;
}

static int spp_of(const image *img)
{
    const char *s = image_attr_value(img, "glint:spp");
    return s ? atoi(s) : 0;
}

static int need_aovs(const char *path, const image *img)
{
    if (image_channel(img, "variance.R") < 0 || image_channel(img, "coverage") < 0) {
        printf("FAIL %s: no variance/coverage channels (render with --aovs)\n", path);
        return 0;
    }
    return 1;
}

/* Standard normal upper quantile: z with P(Z > z) = p (bisection on erfc). */
static double normal_quantile_upper(double p)
{
    double lo = 0.0, hi = 40.0;
    int i;
    for (i = 0; i < 200; i++) {
        const double mid = 0.5 * (lo + hi);
        if (0.5 * erfc(mid / sqrt(2.0)) > p)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

static int mode_furnace(const char *path, double range, double delta, double tol)
{
    image img;
    int ok = 1, c, worst_x = 0, worst_y = 0, nspp;
    size_t p, npix;
    double mean[3] = {0, 0, 0}, worst = 0.0, bound, zmax = 0.0;
    int var_ch;
    if (load(path, &img) != 0)
        return 0;
    ok = check_finite(path, &img);
    nspp = spp_of(&img);
    if (nspp <= 0) {
        printf("FAIL %s: no glint:spp attribute\n", path);
        image_free(&img);
        return 0;
    }
    npix = (size_t)img.width * (size_t)img.height;
    var_ch = image_channel(&img, "variance.R");
    for (p = 0; p < npix; p++)
        for (c = 0; c < 3; c++) {
            const double v = img.pixels[p * (size_t)img.channels + (size_t)c];
            const double dev = fabs(v - 1.0);
            mean[c] += v;
            if (dev > worst) {
                worst = dev;
                worst_x = (int)(p % (size_t)img.width);
                worst_y = (int)(p / (size_t)img.width);
            }
            if (var_ch >= 0) {
                const double var = img.pixels[p * (size_t)img.channels + (size_t)(var_ch + c)];
                if (var > 0.0 && dev / sqrt(var) > zmax)
                    zmax = dev / sqrt(var);
            }
        }
    for (c = 0; c < 3; c++)
        mean[c] /= (double)npix;
    /* Hoeffding with a union bound over every pixel channel; 1e-5 absorbs float rounding
     * when R = 0 (a zero-variance estimator). */
    bound = range * sqrt(log(6.0 * (double)npix / delta) / (2.0 * nspp)) + 1e-5;
    printf("     %s: %d spp, mean (%.5f, %.5f, %.5f), worst pixel (%d, %d) off by %.4f; "
           "Hoeffding bound %.4f (R = %g, delta = %g)",
           path, nspp, mean[0], mean[1], mean[2], worst_x, worst_y, worst, bound, range, delta);
    if (var_ch >= 0)
        printf("; largest |pixel - 1| / its standard error %.2f", zmax);
    printf("\n");
    for (c = 0; c < 3; c++)
        if (fabs(mean[c] - 1.0) > tol) {
            printf("FAIL %s: channel %d mean %.5f is not within %g of 1\n", path, c, mean[c], tol);
            ok = 0;
        }
    if (worst > bound) {
        printf("FAIL %s: pixel (%d, %d) is %.4f from 1, beyond the bound %.4f\n", path, worst_x,
               worst_y, worst, bound);
        ok = 0;
    }
    if (ok)
        printf("ok   %s: white furnace\n", path);
    image_free(&img);
    return ok;
}

static int mode_energy(const char *path, double sigmas)
{
    image img;
    int ok, c, vch, cov;
    size_t p, npix, count = 0;
    double sum[3] = {0, 0, 0}, var[3] = {0, 0, 0}, maxv = 0.0;
    if (load(path, &img) != 0)
        return 0;
    ok = check_finite(path, &img);
    if (!need_aovs(path, &img)) {
        image_free(&img);
        return 0;
    }
    vch = image_channel(&img, "variance.R");
    cov = image_channel(&img, "coverage");
    npix = (size_t)img.width * (size_t)img.height;
    for (p = 0; p < npix; p++) {
        const float *px = &img.pixels[p * (size_t)img.channels];
        if (px[cov] < 1.0f)
            continue;
        count++;
        for (c = 0; c < 3; c++) {
            sum[c] += px[c];
            var[c] += px[vch + c];
            if (px[c] > maxv)
                maxv = px[c];
        }
    }
    if (count == 0) {
        printf("FAIL %s: no pixel fully covered by the object\n", path);
        image_free(&img);
        return 0;
    }
    printf("     %s: %zu object pixels, mean (%.5f, %.5f, %.5f) +- (%.5f, %.5f, %.5f) (1 SE), "
           "brightest pixel %.4f\n",
           path, count, sum[0] / (double)count, sum[1] / (double)count, sum[2] / (double)count,
           sqrt(var[0]) / (double)count, sqrt(var[1]) / (double)count,
           sqrt(var[2]) / (double)count, maxv);
    for (c = 0; c < 3; c++) {
        const double m = sum[c] / (double)count, se = sqrt(var[c]) / (double)count;
        if (m > 1.0 + sigmas * se + 1e-5) {
            printf("FAIL %s: channel %d mean %.5f exceeds 1 by %.1f standard errors\n", path, c,
                   m, (m - 1.0) / se);
            ok = 0;
        }
    }
    if (ok)
        printf("ok   %s: energy <= 1\n", path);
    image_free(&img);
    return ok;
}

typedef struct region_stats {
    double mean[3], var_of_mean[3];
} region_stats;

static region_stats region(const image *img, int x0, int y0, int x1, int y1)
{
    region_stats r;
    const int vch = image_channel(img, "variance.R");
    const double n = (double)(x1 - x0) * (double)(y1 - y0);
    int x, y, c;
    memset(&r, 0, sizeof r);
    for (y = y0; y < y1; y++)
        for (x = x0; x < x1; x++) {
            const float *px = &img->pixels[((size_t)y * (size_t)img->width + (size_t)x) *
                                           (size_t)img->channels];
            for (c = 0; c < 3; c++) {
                r.mean[c] += px[c];
                r.var_of_mean[c] += px[vch + c];
            }
        }
    for (c = 0; c < 3; c++) {
        r.mean[c] /= n;
        r.var_of_mean[c] /= n * n;
    }
    return r;
}

static int mode_agree(int count, char **paths, int blocks, double alpha)
{
    image *imgs = calloc((size_t)count, sizeof *imgs);
    int i, ok = 1, loaded = 0, c, bx, by;
    double z, worst = 0.0;
    long comparisons;
    if (!imgs)
        return 0;
    for (i = 0; i < count; i++) {
        if (load(paths[i], &imgs[i]) != 0) {
            ok = 0;
            break;
        }
        loaded++;
        if (!check_finite(paths[i], &imgs[i]) || !need_aovs(paths[i], &imgs[i]))
            ok = 0;
        if (imgs[i].width != imgs[0].width || imgs[i].height != imgs[0].height) {
            printf("FAIL %s: size differs from %s\n", paths[i], paths[0]);
            ok = 0;
        }
    }
    if (!ok)
        goto out;
    comparisons = (long)(count - 1) * 3L * (1L + (long)blocks * blocks);
    z = normal_quantile_upper(alpha / (2.0 * (double)comparisons));
    printf("     %ld comparisons, threshold %.2f standard errors (alpha %g)\n", comparisons, z,
           alpha);
    {
        const region_stats a = region(&imgs[0], 0, 0, imgs[0].width, imgs[0].height);
        printf("     %-28s mean (%.5f, %.5f, %.5f) +- (%.5f, %.5f, %.5f)\n", paths[0], a.mean[0],
               a.mean[1], a.mean[2], sqrt(a.var_of_mean[0]), sqrt(a.var_of_mean[1]),
               sqrt(a.var_of_mean[2]));
        for (i = 1; i < count; i++) {
            const region_stats b = region(&imgs[i], 0, 0, imgs[i].width, imgs[i].height);
            printf("     %-28s mean (%.5f, %.5f, %.5f) +- (%.5f, %.5f, %.5f), z =", paths[i],
                   b.mean[0], b.mean[1], b.mean[2], sqrt(b.var_of_mean[0]),
                   sqrt(b.var_of_mean[1]), sqrt(b.var_of_mean[2]));
            for (c = 0; c < 3; c++) {
                const double zc = fabs(a.mean[c] - b.mean[c]) /
                                  sqrt(a.var_of_mean[c] + b.var_of_mean[c]);
                printf(" %.2f", zc);
                if (!(zc <= z)) {
                    ok = 0;
                    printf(" (FAIL)");
                }
            }
            printf("\n");
        }
    }
    for (i = 1; i < count; i++) {
        int worst_bx = 0, worst_by = 0, worst_c = 0;
        double wz = 0.0;
        for (by = 0; by < blocks; by++)
            for (bx = 0; bx < blocks; bx++) {
                const int x0 = bx * imgs[0].width / blocks, x1 = (bx + 1) * imgs[0].width / blocks;
                const int y0 = by * imgs[0].height / blocks,
                          y1 = (by + 1) * imgs[0].height / blocks;
                const region_stats a = region(&imgs[0], x0, y0, x1, y1);
                const region_stats b = region(&imgs[i], x0, y0, x1, y1);
                for (c = 0; c < 3; c++) {
                    const double se = sqrt(a.var_of_mean[c] + b.var_of_mean[c]);
                    const double diff = fabs(a.mean[c] - b.mean[c]);
                    const double zc = se > 0.0 ? diff / se : (diff > 1e-6 ? INFINITY : 0.0);
                    if (zc > wz) {
                        wz = zc;
                        worst_bx = bx;
                        worst_by = by;
                        worst_c = c;
                    }
                }
            }
        printf("     %s vs %s: worst of %dx%d blocks: block (%d, %d) channel %d, z = %.2f\n",
               paths[i], paths[0], blocks, blocks, worst_bx, worst_by, worst_c, wz);
        if (!(wz <= z)) {
            printf("FAIL %s: block (%d, %d) differs from %s by %.2f standard errors\n",
                   paths[i], worst_bx, worst_by, paths[0], wz);
            ok = 0;
        }
        if (wz > worst)
            worst = wz;
    }
    if (ok)
        printf("ok   %d images agree (largest z %.2f <= %.2f)\n", count, worst, z);
out:
    for (i = 0; i < loaded; i++)
        image_free(&imgs[i]);
    free(imgs);
    return ok;
}

/* The channels both images have (by name) match value for value: |a - b| <= abs + rel
 * max(|a|, |b|) (0 and 0: identical). */
static int mode_same(const char *pa, const char *pb, double rel, double abs_tol)
{
    image a, b;
    int ok = 1, c, shared = 0;
    size_t p, npix, differ = 0, worst_p = 0;
    double worst = 0.0, worst_a = 0.0, worst_b = 0.0;
    if (load(pa, &a) != 0)
        return 0;
    if (load(pb, &b) != 0) {
        image_free(&a);
        return 0;
    }
    ok = check_finite(pa, &a) & check_finite(pb, &b);
    if (a.width != b.width || a.height != b.height) {
        printf("FAIL %s and %s differ in size\n", pa, pb);
        ok = 0;
        goto out;
    }
    npix = (size_t)a.width * (size_t)a.height;
    for (c = 0; c < a.channels; c++) {
        const int cb = image_channel(&b, a.channel_names[c]);
        if (cb < 0)
            continue;
        shared++;
        for (p = 0; p < npix; p++) {
            const double va = a.pixels[p * (size_t)a.channels + (size_t)c];
            const double vb = b.pixels[p * (size_t)b.channels + (size_t)cb];
            const double excess = fabs(va - vb) - (abs_tol + rel * fmax(fabs(va), fabs(vb)));
            if (va != vb && excess > 0.0) {
                if (differ++ == 0 || excess > worst) {
                    worst = excess;
                    worst_p = p;
                    worst_a = va;
                    worst_b = vb;
                }
            }
        }
    }
    if (shared < 3) {
        printf("FAIL %s and %s share fewer than 3 channels\n", pa, pb);
        ok = 0;
    } else if (differ) {
        printf("FAIL %s and %s: %zu values differ by more than %g + %g x value; the worst at "
               "pixel (%zu, %zu): %.7g vs %.7g\n",
               pa, pb, differ, abs_tol, rel, worst_p % (size_t)a.width, worst_p / (size_t)a.width,
               worst_a, worst_b);
        ok = 0;
    } else if (rel == 0.0 && abs_tol == 0.0)
        printf("ok   %s and %s are identical in their %d shared channels\n", pa, pb, shared);
    else
        printf("ok   %s and %s match within %g + %g x value in their %d shared channels\n", pa,
               pb, abs_tol, rel, shared);
out:
    image_free(&a);
    image_free(&b);
    return ok;
}

static int usage(void)
{
    fprintf(stderr, "usage: ptcheck finite IMG.exr...\n"
                    "       ptcheck furnace IMG.exr --range R [--delta D] [--tol T]\n"
                    "       ptcheck energy IMG.exr [--sigmas K]\n"
                    "       ptcheck agree A.exr B.exr... [--blocks B] [--alpha A]\n"
                    "       ptcheck same A.exr B.exr [--rel R] [--abs A]\n");
    return 2;
}

int main(int argc, char **argv)
{
    double range = -1.0, delta = 1e-6, tol = 0.01, sigmas = 4.0, alpha = 1e-4, rel = 0.0,
           abs_tol = 0.0;
    int blocks = 4, i, nfiles = 0, ok = 1;
    char **files;
    if (argc < 3)
        return usage();
    files = calloc((size_t)argc, sizeof *files);
    if (!files)
        return 2;
    for (i = 2; i < argc; i++) {
        if (strncmp(argv[i], "--", 2) == 0) {
            double *target = NULL;
            if (i + 1 >= argc) {
                free(files);
                return usage();
            }
            if (strcmp(argv[i], "--range") == 0)
                target = &range;
            else if (strcmp(argv[i], "--delta") == 0)
                target = &delta;
            else if (strcmp(argv[i], "--tol") == 0)
                target = &tol;
            else if (strcmp(argv[i], "--sigmas") == 0)
                target = &sigmas;
            else if (strcmp(argv[i], "--alpha") == 0)
                target = &alpha;
            else if (strcmp(argv[i], "--rel") == 0)
                target = &rel;
            else if (strcmp(argv[i], "--abs") == 0)
                target = &abs_tol;
            else if (strcmp(argv[i], "--blocks") == 0)
                blocks = atoi(argv[i + 1]);
            else {
                free(files);
                return usage();
            }
            if (target)
                *target = atof(argv[i + 1]);
            i++;
        } else
            files[nfiles++] = argv[i];
    }
    if (nfiles == 0 || blocks < 1) {
        free(files);
        return usage();
    }
    if (strcmp(argv[1], "finite") == 0) {
        for (i = 0; i < nfiles; i++) {
            image img;
            if (load(files[i], &img) != 0) {
                ok = 0;
                continue;
            }
            ok &= check_finite(files[i], &img);
            image_free(&img);
        }
    } else if (strcmp(argv[1], "furnace") == 0 && nfiles == 1 && range >= 0.0) {
        ok = mode_furnace(files[0], range, delta, tol);
    } else if (strcmp(argv[1], "energy") == 0 && nfiles == 1) {
        ok = mode_energy(files[0], sigmas);
    } else if (strcmp(argv[1], "same") == 0 && nfiles == 2) {
        ok = mode_same(files[0], files[1], rel, abs_tol);
    } else if (strcmp(argv[1], "agree") == 0 && nfiles >= 2) {
        ok = mode_agree(nfiles, files, blocks, alpha);
    } else {
        free(files);
        return usage();
    }
    free(files);
    return ok ? 0 : 1;
}
