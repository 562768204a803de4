/* warpsim's step as a plain single-threaded C program: the speed baseline of `python -m benchmarks -k c-reference`.
 *
 * It does the work of benchmarks/numpy_step.py (and of warpsim's CPU step): the air force per triangle (paper,
 * plate or sail law, and drag bodies), Verlet with damping, K Jacobi iterations of the averaged stick corrections
 * (with the model's per-stick coefficients and per-particle scales, so mass splitting and stick weights are the
 * model's; Chebyshev weights per iteration; elastic sticks as XPBD; the increments carried apart from the starting
 * positions), nails, the momentum the projection moved given back to each free world
 * (warpsim.physics.kernels.momentum; solver.keep_momentum),
 * and the terrain (bilinear heightfield, normal push-out with friction, or a clamp).
 *
 * Precision, as warpsim's kernels: positions, previous positions, nail targets and the projection's origins are
 * double; everything measured from positions (stick vectors, triangle edges, velocities, penetration depth) is a
 * double difference rounded to float, and all the rest is float, with the same operations in the same order as
 * the kernels (so that it agrees with warpsim bit for bit where the sums' order is the same).
 *
 * Usage: step MODEL.bin STEPS OUT.bin [parts] -- reads the model written by benchmarks/c_reference, runs STEPS
 * steps, writes the final positions (float64 [n, 3]) to OUT.bin and prints "seconds steps" of the stepping loop
 * alone; with "parts", also the seconds spent in each part ("air S verlet S constraints S terrain S").
 * Build: cc -O3 -march=native -std=c99 -ffp-contract=off -o step step.c -lm (Warp compiles its CPU kernels for
 * the host CPU too; no fused multiply-adds, as Warp's kernels have none; no OpenMP, no -ffast-math).
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { AIR_PAPER = 0, AIR_PLATE = 1, AIR_SAIL = 2 };
enum { GROUND_NORMAL = 0, GROUND_CLAMP = 1 };

typedef struct {
    int32_t n, s, t, d, k, ny, nx, air, collision, nails, worlds;
    float dt, density, air_scale, relaxation, damping, gx, gy, gz, friction, ox, oy, cx, cy, stall_sharpness;
    double *q, *q_prev, *nail_target; /* positions [m], as warpsim's State and Control */
    float *inv_mass, *coef, *rest, *scale, *omega, *loading, *sail, *tri_wind;
    float *alpha, *lam, *lam_last; /* elastic sticks: compliance / dt^2 [1/kg] (0: rigid), lam and its last step */
    float *drag_area, *drag_wind, *heights;
    int32_t *nail_of, *ends, *tris, *span, *drag;
    int32_t *world_start, *world_particles, *world_free; /* the momentum keeper's worlds (none: keep_momentum off) */
    double base, gox, goy, gcx, gcy; /* the terrain: heights above base [m], grid origin and cell [m], float64 */
} Model;

static void *read_array(FILE *f, size_t count, size_t size) {
    void *p = malloc(count * size + 1);
    if (!p || fread(p, size, count, f) != count) {
        fprintf(stderr, "step: model file too short\n");
        exit(2);
    }
    return p;
}

static void load(const char *path, Model *m) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        exit(2);
    }
    int32_t *ints = read_array(f, 11, 4);
    memcpy(&m->n, ints, 11 * sizeof(int32_t));
    float *floats = read_array(f, 14, 4);
    memcpy(&m->dt, floats, 14 * sizeof(float));
    double *grid = read_array(f, 5, 8);
    m->base = grid[0], m->gox = grid[1], m->goy = grid[2], m->gcx = grid[3], m->gcy = grid[4];
    size_t n = m->n, s = m->s, t = m->t, d = m->d;
    m->q = read_array(f, 3 * n, 8);
    m->q_prev = read_array(f, 3 * n, 8);
    m->inv_mass = read_array(f, n, 4);
    m->nail_of = read_array(f, n, 4);
    m->nail_target = read_array(f, 3 * (size_t)m->nails, 8);
    m->ends = read_array(f, 2 * s, 4);
    m->coef = read_array(f, s, 4);
    m->rest = read_array(f, s, 4);
    m->alpha = read_array(f, s, 4);
    m->lam = malloc(s * sizeof(float) + 1), m->lam_last = malloc(s * sizeof(float) + 1);
    m->scale = read_array(f, n, 4);
    m->omega = read_array(f, (size_t)m->k, 4);
    m->tris = read_array(f, 3 * t, 4);
    m->loading = read_array(f, t, 4);
    m->sail = read_array(f, 4 * t, 4);
    m->span = read_array(f, 2 * t, 4);
    m->tri_wind = read_array(f, 3 * t, 4);
    m->drag = read_array(f, d, 4);
    m->drag_area = read_array(f, d, 4);
    m->drag_wind = read_array(f, 3 * d, 4);
    m->heights = read_array(f, (size_t)m->ny * m->nx, 4);
    m->world_start = read_array(f, (size_t)m->worlds + 1, 4);
    m->world_particles = read_array(f, (size_t)m->world_start[m->worlds], 4);
    m->world_free = read_array(f, (size_t)m->worlds, 4);
    fclose(f);
}

/* bilinear terrain height [m] (float64: float32 heights above a double base, the cell found in double) and its
 * upward unit normal */
static double terrain(const Model *m, double x, double y, float *normal) {
    double fx = (x - m->gox) / m->gcx, fy = (y - m->goy) / m->gcy;
    fx = fmin(fmax(fx, 0.0), (double)(m->nx - 1));
    fy = fmin(fmax(fy, 0.0), (double)(m->ny - 1));
    int ix = (int)floor(fx), iy = (int)floor(fy);
    if (ix > m->nx - 2) ix = m->nx - 2;
    if (iy > m->ny - 2) iy = m->ny - 2;
    float tx = (float)(fx - (double)ix), ty = (float)(fy - (double)iy);
    const float *h = m->heights;
    float h00 = h[iy * m->nx + ix], h10 = h[iy * m->nx + ix + 1];
    float h01 = h[(iy + 1) * m->nx + ix], h11 = h[(iy + 1) * m->nx + ix + 1];
    if (normal) {
        float dx = ((1.0f - ty) * (h10 - h00) + ty * (h11 - h01)) / (float)m->gcx;
        float dy = ((1.0f - tx) * (h01 - h00) + tx * (h11 - h10)) / (float)m->gcy;
        float len = sqrtf(dx * dx + dy * dy + 1.0f);
        normal[0] = -dx / len, normal[1] = -dy / len, normal[2] = 1.0f / len;
    }
    return m->base + (double)((1.0f - ty) * ((1.0f - tx) * h00 + tx * h10) + ty * ((1.0f - tx) * h01 + tx * h11));
}

static float dot3(const float *a, const float *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Warp's sign(): -1 below zero, else 1 (so 1 at zero) */
static float sign1(float x) { return x < 0.0f ? -1.0f : 1.0f; }

/* the sail law (warpsim.physics.kernels.aero.sail_force), before the 1/3 share */
static void sail_force(const Model *m, int tri, const float *n, float area, const float *w, const float *span,
                       float *out) {
    const float *c = m->sail + 4 * tri;
    float speed = sqrtf(dot3(w, w));
    out[0] = out[1] = out[2] = 0.0f;
    if (speed == 0.0f) return;
    float w_hat[3] = {w[0] / speed, w[1] / speed, w[2] / speed};
    float along = dot3(w, span);
    float w_n[3] = {w[0] - span[0] * along, w[1] - span[1] * along, w[2] - span[2] * along};
    float speed_n = sqrtf(dot3(w_n, w_n));
    float force[3], attached[3] = {0.0f, 0.0f, 0.0f};
    for (int i = 0; i < 3; i++) force[i] = w_hat[i] * (c[2] * speed * speed);
    if (speed_n > 1e-6f * speed) {
        float wn_hat[3] = {w_n[0] / speed_n, w_n[1] / speed_n, w_n[2] / speed_n};
        float d = dot3(n, wn_hat);
        float sin_n = fminf(fabsf(d), 1.0f);
        float cos_n = sqrtf(fmaxf(1.0f - sin_n * sin_n, 0.0f));
        float cl = c[0] * asinf(sin_n);
        float sign = sign1(d);
        for (int i = 0; i < 3; i++) {
            float lift_dir = cos_n > 1e-6f ? (n[i] * sign - wn_hat[i] * sin_n) / cos_n : 0.0f;
            attached[i] = (lift_dir * cl + wn_hat[i] * (c[1] * cl * cl)) * (speed_n * speed_n);
        }
    }
    float wn = dot3(n, w_hat);
    float sin_a = fminf(fabsf(wn), 1.0f);
    float sigma = 1.0f / (1.0f + expf(-m->stall_sharpness * (asinf(sin_a) - c[3])));
    float sign = sign1(wn), separated[3] = {0.0f, 0.0f, 0.0f};
    if (sin_a > 1e-6f) {
        float plate = 1.0f / (0.222f + 0.283f / sin_a);
        for (int i = 0; i < 3; i++) separated[i] = n[i] * (sign * plate * speed * speed);
    }
    float scale = 0.5f * m->density * area * (m->loading[tri] + (1.0f - m->loading[tri]) * sin_a);
    for (int i = 0; i < 3; i++) out[i] = (force[i] + (attached[i] * (1.0f - sigma) + separated[i] * sigma)) * scale;
}

/* per-particle air force [N]: each triangle's force, a third to each corner, and the drag bodies */
static void air_force(const Model *m, float *force) {
    memset(force, 0, sizeof(float) * 3 * (size_t)m->n);
    const double *q = m->q, *qp = m->q_prev;
    for (int t = 0; t < m->t; t++) {
        const int32_t *v = m->tris + 3 * t;
        const double *a = q + 3 * v[0], *b = q + 3 * v[1], *c = q + 3 * v[2];
        float ab[3], bc[3], cr[3], vel[3], w[3], f[3];
        for (int i = 0; i < 3; i++) ab[i] = (float)(b[i] - a[i]), bc[i] = (float)(c[i] - b[i]);
        cr[0] = ab[1] * bc[2] - ab[2] * bc[1];
        cr[1] = ab[2] * bc[0] - ab[0] * bc[2];
        cr[2] = ab[0] * bc[1] - ab[1] * bc[0];
        float len = sqrtf(dot3(cr, cr));
        if (len == 0.0f) continue;
        float n[3] = {cr[0] / len, cr[1] / len, cr[2] / len}, area = 0.5f * len;
        for (int i = 0; i < 3; i++) {
            double moved = (a[i] - qp[3 * v[0] + i]) + (b[i] - qp[3 * v[1] + i]) + (c[i] - qp[3 * v[2] + i]);
            vel[i] = (float)moved / (3.0f * m->dt);
            w[i] = m->tri_wind[3 * t + i] - vel[i];
        }
        if (m->air == AIR_SAIL) {
            float span[3] = {0.0f, 0.0f, 0.0f};
            const int32_t *e = m->span + 2 * t;
            if (e[0] >= 0) {
                for (int i = 0; i < 3; i++) span[i] = (float)(q[3 * e[1] + i] - q[3 * e[0] + i]);
                float sl = sqrtf(dot3(span, span));
                for (int i = 0; i < 3; i++) span[i] = sl > 0.0f ? span[i] / sl : 0.0f;
            }
            sail_force(m, t, n, area, w, span, f);
        } else {
            float wn = dot3(n, w), mag;
            if (m->air == AIR_PAPER) {
                mag = m->density * wn * fabsf(wn) * area;
            } else {
                float speed = sqrtf(dot3(w, w));
                float sin_alpha = speed > 0.0f ? fabsf(wn) / speed : 0.0f;
                if (speed == 0.0f || sin_alpha < 1e-6f) continue;
                float cn = (1.0f / (0.222f + 0.283f / sin_alpha)) * (m->loading[t] + (1.0f - m->loading[t]) * sin_alpha);
                mag = 0.5f * m->density * speed * speed * area * cn * sign1(wn);
            }
            for (int i = 0; i < 3; i++) f[i] = n[i] * mag;
        }
        for (int j = 0; j < 3; j++)
            for (int i = 0; i < 3; i++) force[3 * v[j] + i] += f[i] * (m->air_scale / 3.0f);
    }
    if (m->air != AIR_SAIL) return;
    for (int k = 0; k < m->d; k++) {
        int p = m->drag[k];
        float w[3];
        for (int i = 0; i < 3; i++) w[i] = m->drag_wind[3 * k + i] - (float)(q[3 * p + i] - qp[3 * p + i]) / m->dt;
        float mag = 0.5f * m->density * sqrtf(dot3(w, w)) * m->drag_area[k] * m->air_scale;
        for (int i = 0; i < 3; i++) force[3 * p + i] += w[i] * mag;
    }
}

static void verlet(Model *m, const float *force) {
    float g[3] = {m->gx, m->gy, m->gz}, dt2 = m->dt * m->dt;
    double keep = 1.0 - (double)m->damping;
    for (int p = 0; p < m->n; p++) {
        double *x = m->q + 3 * p, *xp = m->q_prev + 3 * p;
        if (m->nail_of[p] >= 0) {
            for (int i = 0; i < 3; i++) xp[i] = x[i], x[i] = m->nail_target[3 * m->nail_of[p] + i];
            continue;
        }
        for (int i = 0; i < 3; i++) {
            double now = x[i];
            if (m->inv_mass[p] != 0.0f) /* the float a dt^2 added to the double positions */
                x[i] = now + (now - xp[i]) * keep + (double)((g[i] + force[3 * p + i] * m->inv_mass[p]) * dt2);
            xp[i] = now;
        }
    }
}

static void project(Model *m, double *origin, float *offset, float *last, float *total) {
    size_t n3 = 3 * (size_t)m->n;
    memcpy(origin, m->q, n3 * sizeof(double));
    memset(offset, 0, n3 * sizeof(float));
    memset(last, 0, n3 * sizeof(float));
    memset(m->lam, 0, (size_t)m->s * sizeof(float));
    memset(m->lam_last, 0, (size_t)m->s * sizeof(float));
    for (int it = 0; it < m->k; it++) {
        float omega = m->omega[it];
        memset(total, 0, n3 * sizeof(float));
        for (int s = 0; s < m->s; s++) {
            int a = m->ends[2 * s], b = m->ends[2 * s + 1];
            const double *qa = m->q + 3 * a, *qb = m->q + 3 * b;
            float d[3] = {(float)(qb[0] - qa[0]), (float)(qb[1] - qa[1]), (float)(qb[2] - qa[2])};
            float len = sqrtf(dot3(d, d));
            float k = 0.0f, alpha = m->alpha[s];
            if (len > 0.0f && alpha > 0.0f) { /* XPBD, as warpsim's compliant_correction */
                float dlam = m->coef[s] * ((len - m->rest[s]) - alpha * m->lam[s]) / (1.0f + alpha * m->coef[s]);
                float inc = m->relaxation * dlam;
                if (omega != 1.0f) inc = inc * omega + m->lam_last[s] * (omega - 1.0f);
                m->lam[s] += inc, m->lam_last[s] = inc;
                k = dlam / len;
            } else if (len > 0.0f) {
                k = m->coef[s] * (len - m->rest[s]) / len;
            }
            for (int i = 0; i < 3; i++) total[3 * a + i] += d[i] * k, total[3 * b + i] -= d[i] * k;
        }
        for (int p = 0; p < m->n; p++) {
            float step = m->relaxation * m->scale[p];
            if (step == 0.0f) { /* nailed particles have scale 0 (as in warpsim's fused scheme) */
                if (m->nail_of[p] >= 0)
                    for (int i = 0; i < 3; i++) m->q[3 * p + i] = m->nail_target[3 * m->nail_of[p] + i];
                continue;
            }
            for (int i = 0; i < 3; i++) {
                float inc = total[3 * p + i] * step;
                if (omega != 1.0f) inc = inc * omega + last[3 * p + i] * (omega - 1.0f);
                offset[3 * p + i] += inc;
                last[3 * p + i] = inc;
                m->q[3 * p + i] = origin[3 * p + i] + (double)offset[3 * p + i];
            }
        }
    }
}

/* the terrain is looked up at the float-rounded position, the corrections made in float and added in double */
static void cross3d(const double *a, const double *b, double *out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* warpsim.physics.kernels.momentum: give each free world back the linear and angular momentum the projection moved
 * (x -= dP / M + I^-1 dL x r), in double, with the kernel's operations in its order; `predicted` holds the
 * positions before the projection */
static void keep_momentum(Model *m, const double *predicted) {
    const double *qp = m->q_prev;
    for (int w = 0; w < m->worlds; w++) {
        if (m->world_free[w] == 0) continue;
        int start = m->world_start[w], end = m->world_start[w + 1];
        double mass = 0.0, centre[3] = {0.0, 0.0, 0.0};
        for (int k = start; k < end; k++) { /* mass centre at the step's start */
            int i = m->world_particles[k];
            double mi = 1.0 / (double)m->inv_mass[i];
            mass += mi;
            for (int c = 0; c < 3; c++) centre[c] += qp[3 * i + c] * mi;
        }
        for (int c = 0; c < 3; c++) centre[c] = centre[c] / mass;
        double dp[3] = {0.0, 0.0, 0.0}, dl[3] = {0.0, 0.0, 0.0}, inertia[3][3] = {{0.0}};
        for (int k = start; k < end; k++) { /* momentum the projection added, inertia about the centre */
            int i = m->world_particles[k];
            double mi = 1.0 / (double)m->inv_mass[i], r[3], delta[3], turn[3];
            for (int c = 0; c < 3; c++) r[c] = qp[3 * i + c] - centre[c], delta[c] = m->q[3 * i + c] - predicted[3 * i + c];
            cross3d(r, delta, turn);
            double rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
            for (int c = 0; c < 3; c++) dp[c] += delta[c] * mi, dl[c] += turn[c] * mi;
            for (int a = 0; a < 3; a++)
                for (int b = 0; b < 3; b++) inertia[a][b] += ((a == b ? rr : 0.0) - r[a] * r[b]) * mi;
        }
        double spin[3] = {0.0, 0.0, 0.0}, shift[3], row12[3];
        double size = inertia[0][0] + inertia[1][1] + inertia[2][2];
        for (int a = 0; a < 3; a++) inertia[a][a] = inertia[a][a] + size * 1.0e-9; /* a line has no inertia about it */
        cross3d(inertia[1], inertia[2], row12);
        double det = inertia[0][0] * row12[0] + inertia[0][1] * row12[1] + inertia[0][2] * row12[2];
        if (size > 0.0) { /* spin = I^-1 dL (Warp's inverse) */
            const double(*I)[3] = inertia;
            double inv[3][3] = {
                {I[1][1] * I[2][2] - I[1][2] * I[2][1], I[0][2] * I[2][1] - I[0][1] * I[2][2], I[0][1] * I[1][2] - I[0][2] * I[1][1]},
                {I[1][2] * I[2][0] - I[1][0] * I[2][2], I[0][0] * I[2][2] - I[0][2] * I[2][0], I[0][2] * I[1][0] - I[0][0] * I[1][2]},
                {I[1][0] * I[2][1] - I[1][1] * I[2][0], I[0][1] * I[2][0] - I[0][0] * I[2][1], I[0][0] * I[1][1] - I[0][1] * I[1][0]},
            };
            double rcp = 1.0 / det;
            for (int a = 0; a < 3; a++) {
                for (int b = 0; b < 3; b++) inv[a][b] = inv[a][b] * rcp;
                spin[a] = inv[a][0] * dl[0] + inv[a][1] * dl[1] + inv[a][2] * dl[2];
            }
        }
        for (int c = 0; c < 3; c++) shift[c] = dp[c] / mass;
        for (int k = start; k < end; k++) {
            int i = m->world_particles[k];
            double r[3], turn[3];
            for (int c = 0; c < 3; c++) r[c] = qp[3 * i + c] - centre[c];
            cross3d(spin, r, turn);
            for (int c = 0; c < 3; c++) m->q[3 * i + c] = m->q[3 * i + c] - shift[c] - turn[c];
        }
    }
}

/* the projection, with the momentum kept where a world is free (as SolverVerlet: both are "constraints") */
static void constrain(Model *m, double *origin, float *offset, float *last, float *total, double *predicted) {
    int any_free = 0;
    for (int w = 0; w < m->worlds; w++) any_free |= m->world_free[w] != 0;
    if (any_free) memcpy(predicted, m->q, 3 * (size_t)m->n * sizeof(double));
    project(m, origin, offset, last, total);
    if (any_free) keep_momentum(m, predicted);
}

static void collide(Model *m) {
    for (int p = 0; p < m->n; p++) {
        if (m->inv_mass[p] == 0.0f) continue;
        double *x = m->q + 3 * p;
        double h = terrain(m, x[0], x[1], NULL);
        if (x[2] >= h) continue;
        if (m->collision == GROUND_NORMAL) {
            float nrm[3], move[3], slide[3];
            terrain(m, x[0], x[1], nrm);
            float depth = (float)(h - x[2]) * nrm[2];
            for (int i = 0; i < 3; i++) x[i] += (double)(nrm[i] * depth);
            for (int i = 0; i < 3; i++) move[i] = (float)(x[i] - m->q_prev[3 * p + i]);
            float along = dot3(move, nrm);
            for (int i = 0; i < 3; i++) slide[i] = move[i] - nrm[i] * along;
            float sl = sqrtf(dot3(slide, slide));
            if (sl > 0.0f) {
                float cut = fminf(1.0f, m->friction * depth / sl);
                for (int i = 0; i < 3; i++) x[i] -= (double)(slide[i] * cut);
            }
            h = terrain(m, x[0], x[1], NULL);
        }
        x[2] = fmax(x[2], h);
    }
}

int main(int argc, char **argv) {
    if (argc != 4 && !(argc == 5 && strcmp(argv[4], "parts") == 0)) {
        fprintf(stderr, "usage: step MODEL.bin STEPS OUT.bin [parts]\n");
        return 2;
    }
    int parts = argc == 5;
    Model m;
    load(argv[1], &m);
    long steps = atol(argv[2]);
    size_t n3 = 3 * (size_t)m.n;
    float *force = malloc(n3 * sizeof(float));
    double *origin = malloc(n3 * sizeof(double)), *predicted = malloc(n3 * sizeof(double));
    float *offset = malloc(n3 * sizeof(float)), *last = malloc(n3 * sizeof(float)), *total = malloc(n3 * sizeof(float));
    struct timespec t0, t1, a, b;
    double spent[4] = {0.0, 0.0, 0.0, 0.0};
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if (!parts) {
        for (long i = 0; i < steps; i++) {
            air_force(&m, force);
            verlet(&m, force);
            constrain(&m, origin, offset, last, total, predicted);
            collide(&m);
        }
    } else { /* the same loop, each part timed (the clock reads cost a little) */
        for (long i = 0; i < steps; i++) {
            for (int part = 0; part < 4; part++) {
                clock_gettime(CLOCK_MONOTONIC, &a);
                if (part == 0) air_force(&m, force);
                if (part == 1) verlet(&m, force);
                if (part == 2) constrain(&m, origin, offset, last, total, predicted);
                if (part == 3) collide(&m);
                clock_gettime(CLOCK_MONOTONIC, &b);
                spent[part] += (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec);
            }
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    FILE *f = fopen(argv[3], "wb");
    if (!f || fwrite(m.q, sizeof(double), n3, f) != n3) {
        perror(argv[3]);
        return 2;
    }
    fclose(f);
    printf("%.9f %ld", (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec), steps);
    if (parts) printf(" air %.9f verlet %.9f constraints %.9f terrain %.9f", spent[0], spent[1], spent[2], spent[3]);
    printf("\n");
    return 0;
}
