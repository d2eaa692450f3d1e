/*
 * RKN12(10): the 17-stage embedded Runge-Kutta-Nystrom pair of Dormand, El-Mikkawy & Prince,
 * "High-order embedded Runge-Kutta-Nystrom formulae", IMA J. Numer. Anal. 7 (1987) 423-430,
 * for second-order systems z'' = g(t, z) (no dependence on z'), driving a CasADi-generated
 * acceleration. The tableau (RKN_C, RKN_A, RKN_B, RKN_BP and the error weights RKN_EB =
 * b - b_hat, RKN_EBP = b' - b'_hat) is emitted above this file by tapp.dynamics.compiled from
 * the exact rationals of tapp/dynamics/rkn12_tableau.txt. The right-hand-side context, the
 * ephemeris evaluation and the norm come from driver_common.c.
 *
 * The vector passed in and out is y = [z, z'] (ny = 2 n2). Step-size control: the order-10
 * estimate on the first n_err components of z and of z', scaled RMS norm as in DOP853
 * (Hairer, Norsett & Wanner I, Sec. II.4), exponent 1/11. The first stage of a step is the
 * acceleration at its start, so it is taken from the previous step (17 evaluations a step,
 * one of them at the step's end).
 *
 * Dense output: the pair has no continuous extension, so outputs come from the confluent
 * Hermite polynomial through (z, z', z'') at six consecutive step ends (degree 17; Hairer,
 * Norsett & Wanner I, Sec. II.6; confluent divided differences as in Stoer & Bulirsch,
 * Sec. 2.1.5; one new row of differences a step), evaluated in Newton form by Horner's rule,
 * outputs side by side. An output in step j, [t_j, t_{j+1}], uses step ends j-2 .. j+3 (clamped at
 * the two ends of the arc), so it is written three steps late; z' at an output is the
 * derivative of that polynomial. Four step ends (degree 11) left 0.2 mm of interpolation
 * error on a J2 LEO day at 1e-12, above the 0.01-0.02 mm step error; six leave 2 um.
 *
 * Return codes as the DOP853 driver (tapp.dynamics.compiled.STATUS).
 */
#define RKN_STAGES 17
#define RKN_SAFETY 0.9
#define RKN_MIN_FACTOR 0.2
#define RKN_MAX_FACTOR 5.0
#define RKN_ORDER_EXP (-1.0 / 11.0)
#define HERMITE_NODES 6
#define HERMITE_N (3 * HERMITE_NODES)
/* An output in step j is written once step end j + HERMITE_AHEAD is known. */
#define HERMITE_AHEAD (HERMITE_NODES / 2)
/* Ring buffer of step ends: a power of two >= HERMITE_NODES, so that a slot is a mask. */
#define RING 8
#define SLOT(m) ((size_t)(m) & (RING - 1))
/* Outputs evaluated side by side (Horner is latency-bound for one output). */
#define DENSE_BATCH 16
/* Inlined into each caller, so that the state case (n2 = 3) is compiled with n2 constant. */
#define INLINE static inline __attribute__((always_inline))

/* The last HERMITE_NODES step ends (ring buffer), the divided differences ending at the last
 * one, and the outputs still to write. */
typedef struct {
    long count;                /* step ends received so far */
    double t[RING];
    double *node;              /* RING x (z, z'), each n2 */
    double *dd;                /* HERMITE_N x n2: f[y_{J-k}, .., y_J], k = 0 .. */
    int n_dd;                  /* rows of dd in use: 3 min(count, HERMITE_NODES) */
    int nout;
    const double *tout;
    double *yout;
    int k_out;                 /* next output to write */
    double dir;
} dense_t;

INLINE double *node_slot(dense_t *d, long m, int n2) {
    return d->node + SLOT(m) * 2 * n2;
}

/* Append a step end, thrice (z, then z' and z''/2 as the confluent differences), to the points
 * y_0, y_1, ... (times in s) and update the last row of the divided-difference table,
 * dd[k] = f[y_{J-k}, .., y_J], in place (Stoer & Bulirsch, Sec. 2.1.5): only the differences
 * over the last HERMITE_NODES step ends are kept. */
INLINE void dense_add(dense_t *d, double t, const double *z, const double *zd,
                      const double *zdd, int n2) {
    double *slot = node_slot(d, d->count, n2);
    d->t[SLOT(d->count)] = t;
    memcpy(slot, z, sizeof(double) * (size_t)n2);
    memcpy(slot + n2, zd, sizeof(double) * (size_t)n2);
    d->count++;
    int w = d->count < HERMITE_NODES ? (int)d->count : HERMITE_NODES;
    double inv[HERMITE_N];
    for (int copy = 0; copy < 3; ++copy) {
        int n = 3 * (w - 1) + copy + 1;  /* rows after this append */
        for (int k = copy + 1; k < n; ++k)  /* y_J - y_{J-k}: another step end */
            inv[k] = 1.0 / (t - d->t[SLOT(d->count - 1 - (k - copy + 2) / 3)]);
        for (int i = 0; i < n2; ++i) {
            double *col = d->dd + i;
            double old = col[0];  /* f[y_{J-1-(k-1)}, .., y_{J-1}] before it is replaced */
            col[0] = z[i];
            if (copy >= 1) { double o = col[n2]; col[n2] = zd[i]; old = o; }
            if (copy >= 2) { double o = col[2 * n2]; col[2 * n2] = 0.5 * zdd[i]; old = o; }
            for (int k = copy + 1; k < n; ++k) {
                double o = col[(size_t)k * n2];
                col[(size_t)k * n2] = (col[(size_t)(k - 1) * n2] - old) * inv[k];
                old = o;
            }
        }
    }
    d->n_dd = 3 * w;
}

/* Evaluate the Newton form (points from the last back: step end times tb[0] = newest, ...)
 * and its derivative at nb times ts into rows out[b] ([z, z'], 2 n2 each): one Horner
 * recurrence over the table, the outputs side by side so their independent chains overlap. */
INLINE void dense_batch(const dense_t *d, const double *tb, int nb, const double *ts,
                        double *const *out, int n2) {
    const double *dd = d->dd;
    int n = d->n_dd;
    for (int b = 0; b < nb; ++b)
        for (int i = 0; i < n2; ++i) { out[b][i] = dd[(n - 1) * n2 + i]; out[b][n2 + i] = 0.0; }
    for (int k = n - 2; k >= 0; --k) {
        const double *row = dd + k * n2;
        double tk = tb[k / 3];
        for (int b = 0; b < nb; ++b) {
            double u = ts[b] - tk;
            double *restrict o = out[b];
            for (int i = 0; i < n2; ++i) {
                o[n2 + i] = o[n2 + i] * u + o[i];
                o[i] = o[i] * u + row[i];
            }
        }
    }
}

/* Write every output up to t_limit (inclusive, in the direction of integration) from the
 * Hermite polynomial through the buffered step ends; an output on a step end is copied. */
INLINE void dense_emit(dense_t *d, double t_limit, int n2) {
    int w = d->count < HERMITE_NODES ? (int)d->count : HERMITE_NODES, nb = 0;
    double tb[HERMITE_NODES], ts[DENSE_BATCH];
    double *out[DENSE_BATCH];
    for (int b = 0; b < w; ++b) tb[b] = d->t[SLOT(d->count - 1 - b)];
    for (; d->k_out < d->nout && d->dir * (d->tout[d->k_out] - t_limit) <= 0; d->k_out++) {
        double tk = d->tout[d->k_out];
        double *row = d->yout + (size_t)d->k_out * 2 * n2;
        int hit = -1;
        for (int b = 0; b < w; ++b) if (tb[b] == tk) hit = b;
        if (hit >= 0) {
            memcpy(row, node_slot(d, d->count - 1 - hit, n2), sizeof(double) * 2 * (size_t)n2);
            continue;
        }
        ts[nb] = tk;
        out[nb++] = row;
        if (nb == DENSE_BATCH) { dense_batch(d, tb, nb, ts, out, n2); nb = 0; }
    }
    if (nb) dense_batch(d, tb, nb, ts, out, n2);
}

/* Scaled RMS size of (z, z') and of (z', z'') over the first n_err components of each. */
static double rms_pair(const double *a, const double *b, const double *scale_a,
                       const double *scale_b, int n_err) {
    double sa = rms_scaled(a, scale_a, n_err), sb = rms_scaled(b, scale_b, n_err);
    return sqrt(0.5 * (sa * sa + sb * sb));
}

/* The integration of tapp_integrate for n2 components (a constant where inlined). */
INLINE int rkn_run(ctx_t *cx, int n2, double t0, const double *y0, dense_t *dn, double rtol,
                   double atol, int n_err, long max_steps, double *work, long *n_acc,
                   long *n_rej) {
    double *K = work;
    double *z = work + RKN_STAGES * (size_t)n2;
    double *zd = z + n2, *z_new = z + 2 * n2, *zd_new = z + 3 * n2, *ztmp = z + 4 * n2;
    double *scale = z + 5 * n2;
    int status = 0;
    memcpy(z, y0, sizeof(double) * 2 * (size_t)n2);
    double t = t0;
    double t_end = dn->tout[dn->nout - 1];
    double dir = dn->dir;
    rhs(cx, t, z, K);
    dense_add(dn, t, z, zd, K, n2);
    dense_emit(dn, t0, n2);
    /* Initial step: Hairer, Norsett & Wanner, Sec. II.4, on the first-order form. */
    double h_abs;
    {
        for (int i = 0; i < n_err; ++i) {
            scale[i] = atol + fabs(z[i]) * rtol;
            ztmp[i] = atol + fabs(zd[i]) * rtol;
        }
        double d0 = rms_pair(z, zd, scale, ztmp, n_err), d1 = rms_pair(zd, K, scale, ztmp, n_err);
        double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
        double *g1 = K + n2, *dz = K + 2 * (size_t)n2;
        for (int i = 0; i < n2; ++i) z_new[i] = z[i] + h0 * dir * zd[i];
        rhs(cx, t + h0 * dir, z_new, g1);
        for (int i = 0; i < n_err; ++i) { dz[i] = h0 * K[i]; g1[i] -= K[i]; }
        double d2 = rms_pair(dz, g1, scale, ztmp, n_err) / h0;
        double dmax = d1 > d2 ? d1 : d2;
        double h1 = (dmax <= 1e-15) ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dmax, 1.0 / 12.0);
        h_abs = fmin(100.0 * h0, h1);
    }
    int rejected = 0;
    while (dn->k_out < dn->nout) {
        if (t == t_end) { dense_emit(dn, t_end, n2); break; }
        if (*n_acc + *n_rej >= max_steps) { status = 1; break; }
        double min_step = 10.0 * fabs(nextafter(t, dir * INFINITY) - t);
        if (h_abs < min_step) { status = 2; break; }
        double h = h_abs * dir;
        double t_new = t + h;
        if (dir * (t_new - t_end) > 0) { t_new = t_end; h = t_new - t; h_abs = fabs(h); }
        double h2 = h * h;
        for (int s = 1; s < RKN_STAGES; ++s) {
            double ch = RKN_C[s] * h;
            for (int i = 0; i < n2; ++i) ztmp[i] = 0.0;
            for (int j = 0; j < s; ++j) {
                double a = RKN_A[s][j];
                if (a == 0.0) continue;
                for (int i = 0; i < n2; ++i) ztmp[i] += a * K[(size_t)j * n2 + i];
            }
            for (int i = 0; i < n2; ++i) ztmp[i] = z[i] + ch * zd[i] + h2 * ztmp[i];
            rhs(cx, t + ch, ztmp, K + (size_t)s * n2);
        }
        if (cx->eph_error) { status = 4; break; }
        double sum = 0.0;
        for (int i = 0; i < n2; ++i) {
            double b = 0.0, bp = 0.0, eb = 0.0, ebp = 0.0;
            for (int j = 0; j < RKN_STAGES; ++j) {
                double k = K[(size_t)j * n2 + i];
                b += RKN_B[j] * k; bp += RKN_BP[j] * k; eb += RKN_EB[j] * k; ebp += RKN_EBP[j] * k;
            }
            z_new[i] = z[i] + h * zd[i] + h2 * b;
            zd_new[i] = zd[i] + h * bp;
            if (i < n_err) {
                double ez = h2 * eb / (atol + rtol * fmax(fabs(z[i]), fabs(z_new[i])));
                double ezd = h * ebp / (atol + rtol * fmax(fabs(zd[i]), fabs(zd_new[i])));
                sum += ez * ez + ezd * ezd;
            }
        }
        double err = sqrt(sum / (2.0 * n_err));
        if (!isfinite(err)) {
            h_abs *= RKN_MIN_FACTOR; rejected = 1; ++*n_rej; continue;
        }
        if (err < 1.0) {
            double factor = (err == 0.0) ? RKN_MAX_FACTOR
                                         : fmin(RKN_MAX_FACTOR, RKN_SAFETY * pow(err, RKN_ORDER_EXP));
            if (rejected && factor > 1.0) factor = 1.0;
            int finite = 1;
            for (int i = 0; i < 2 * n2; ++i) if (!isfinite(z_new[i])) { finite = 0; break; }
            if (!finite) { status = 3; break; }
            t = t_new;
            memcpy(z, z_new, sizeof(double) * 2 * (size_t)n2);
            rhs(cx, t, z, K); /* the next step's first stage */
            if (cx->eph_error) { status = 4; break; }
            dense_add(dn, t, z, zd, K, n2);
            if (dn->count >= HERMITE_NODES)
                dense_emit(dn, dn->t[SLOT(dn->count - HERMITE_AHEAD)], n2);
            h_abs *= factor;
            rejected = 0;
            ++*n_acc;
        } else {
            h_abs *= fmax(RKN_MIN_FACTOR, RKN_SAFETY * pow(err, RKN_ORDER_EXP));
            rejected = 1;
            ++*n_rej;
        }
    }
    return status;
}

/*
 * Integrate z'' = g(t, z) from (t0, [z0, z0']) through the monotonic output times
 * tout[0..nout-1] (either direction), writing [z, z'](tout[k]) to yout[k*ny ...].
 * stats[0..2] = accepted steps, rejected steps, RHS evaluations.
 */
int tapp_integrate(int which, int ny, double t0, const double *y0, int nout, const double *tout,
                   double *yout, const double *q, const double *c, const double *eph, int nb,
                   int nseg, int ncoef, double eph_t0, double eph_h, double rtol, double atol,
                   int n_err, long max_steps, double *stats) {
    int n2 = ny / 2;
    ctx_t cx;
    ctx_open(&cx, which, n2, q, c, eph, nb, nseg, ncoef, eph_t0, eph_h);
    double *work = malloc(sizeof(double) * (RKN_STAGES + 6) * (size_t)n2);
    dense_t dn = {0, {0}, malloc(sizeof(double) * RING * 2 * (size_t)n2),
                  malloc(sizeof(double) * HERMITE_N * (size_t)n2), 0, nout, tout, yout, 0,
                  (tout[nout - 1] >= t0) ? 1.0 : -1.0};
    long n_acc = 0, n_rej = 0;
    int status = n2 == 3
        ? rkn_run(&cx, 3, t0, y0, &dn, rtol, atol, n_err, max_steps, work, &n_acc, &n_rej)
        : rkn_run(&cx, n2, t0, y0, &dn, rtol, atol, n_err, max_steps, work, &n_acc, &n_rej);
    stats[0] = (double)n_acc; stats[1] = (double)n_rej; stats[2] = (double)cx.nfev;
    ctx_close(&cx);
    free(work); free(dn.node); free(dn.dd);
    return status;
}
