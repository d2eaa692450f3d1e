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
 * Hermite polynomial through (z, z', z'') at four consecutive step ends (degree 11, error
 * O(h^12) like the step; Hairer, Norsett & Wanner I, Sec. II.6 and the divided differences of
 * Stoer & Bulirsch, Sec. 2.1.5). An output in step j, [t_j, t_{j+1}], uses step ends
 * j-1 .. j+2 (clamped at the two ends of the arc), so it is written one step late; z' at an
 * output is the derivative of that polynomial.
 *
 * Return codes as the DOP853 driver (tapp.dynamics.compiled.STATUS).
 */
#define RKN_STAGES 17
#define RKN_SAFETY 0.9
#define RKN_MIN_FACTOR 0.2
#define RKN_MAX_FACTOR 5.0
#define RKN_ORDER_EXP (-1.0 / 11.0)
#define HERMITE_NODES 4
#define HERMITE_N (3 * HERMITE_NODES)

/* The last HERMITE_NODES step ends (ring buffer) and the outputs still to write. */
typedef struct {
    int n2;
    long count;                /* step ends received so far */
    double t[HERMITE_NODES];
    double *node;              /* HERMITE_NODES x (z, z', z''), each n2 */
    double *dd;                /* HERMITE_N x n2 divided differences */
    int nout;
    const double *tout;
    double *yout;
    int k_out;                 /* next output to write */
    double dir;
} dense_t;

static double *node_slot(dense_t *d, long m) {
    return d->node + (size_t)(m % HERMITE_NODES) * 3 * d->n2;
}

static void dense_add(dense_t *d, double t, const double *z, const double *zd,
                      const double *zdd) {
    double *slot = node_slot(d, d->count);
    int n2 = d->n2;
    d->t[d->count % HERMITE_NODES] = t;
    memcpy(slot, z, sizeof(double) * (size_t)n2);
    memcpy(slot + n2, zd, sizeof(double) * (size_t)n2);
    memcpy(slot + 2 * n2, zdd, sizeof(double) * (size_t)n2);
    d->count++;
}

/* Write every output up to t_limit (inclusive, in the direction of integration) from the
 * Hermite polynomial through the buffered step ends. */
static void dense_emit(dense_t *d, double t_limit) {
    int n2 = d->n2;
    long first = d->count > HERMITE_NODES ? d->count - HERMITE_NODES : 0;
    int w = (int)(d->count - first), n = 3 * w;
    double t_ref = d->t[first % HERMITE_NODES];
    double scale = d->t[(d->count - 1) % HERMITE_NODES] - t_ref;
    double x[HERMITE_N];
    int built = 0;
    while (d->k_out < d->nout && d->dir * (d->tout[d->k_out] - t_limit) <= 0) {
        double tk = d->tout[d->k_out];
        double *out = d->yout + (size_t)d->k_out * 2 * n2;
        long hit = -1;
        for (long m = first; m < d->count; ++m) if (d->t[m % HERMITE_NODES] == tk) hit = m;
        if (hit >= 0) {
            memcpy(out, node_slot(d, hit), sizeof(double) * 2 * (size_t)n2);
            d->k_out++;
            continue;
        }
        if (!built) {
            for (int a = 0; a < w; ++a) {
                double s = (d->t[(first + a) % HERMITE_NODES] - t_ref) / scale;
                x[3 * a] = x[3 * a + 1] = x[3 * a + 2] = s;
            }
            for (int i = 0; i < n2; ++i) {
                double *col = d->dd;
                for (int idx = 0; idx < n; ++idx) col[idx * n2 + i] = node_slot(d, first + idx / 3)[i];
                for (int k = 1; k < n; ++k) {
                    for (int idx = n - 1; idx >= k; --idx) {
                        if (x[idx] == x[idx - k]) {
                            const double *nd = node_slot(d, first + idx / 3);
                            col[idx * n2 + i] = k == 1 ? nd[n2 + i] * scale
                                                       : 0.5 * nd[2 * n2 + i] * scale * scale;
                        } else {
                            col[idx * n2 + i] = (col[idx * n2 + i] - col[(idx - 1) * n2 + i]) /
                                                (x[idx] - x[idx - k]);
                        }
                    }
                }
            }
            built = 1;
        }
        double s = (tk - t_ref) / scale;
        for (int i = 0; i < n2; ++i) {
            double p = d->dd[(n - 1) * n2 + i], dp = 0.0;
            for (int idx = n - 2; idx >= 0; --idx) {
                dp = dp * (s - x[idx]) + p;
                p = p * (s - x[idx]) + d->dd[idx * n2 + i];
            }
            out[i] = p;
            out[n2 + i] = dp / scale;
        }
        d->k_out++;
    }
}

/* Scaled RMS size of (z, z') and of (z', z'') over the first n_err components of each. */
static double rms_pair(const double *a, const double *b, const double *scale_a,
                       const double *scale_b, int n_err) {
    double sa = rms_scaled(a, scale_a, n_err), sb = rms_scaled(b, scale_b, n_err);
    return sqrt(0.5 * (sa * sa + sb * sb));
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
    double *K = malloc(sizeof(double) * RKN_STAGES * (size_t)n2);
    double *z = malloc(sizeof(double) * 6 * (size_t)n2);
    double *zd = z + n2, *z_new = z + 2 * n2, *zd_new = z + 3 * n2, *ztmp = z + 4 * n2;
    double *scale = z + 5 * n2;
    dense_t dn = {n2, 0, {0}, malloc(sizeof(double) * HERMITE_NODES * 3 * (size_t)n2),
                  malloc(sizeof(double) * HERMITE_N * (size_t)n2), nout, tout, yout, 0, 0.0};
    int status = 0;
    long n_acc = 0, n_rej = 0;
    memcpy(z, y0, sizeof(double) * 2 * (size_t)n2);
    double t = t0;
    double t_end = tout[nout - 1];
    double dir = (t_end >= t0) ? 1.0 : -1.0;
    dn.dir = dir;
    rhs(&cx, t, z, K);
    dense_add(&dn, t, z, zd, K);
    dense_emit(&dn, t0);
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
        rhs(&cx, t + h0 * dir, z_new, g1);
        for (int i = 0; i < n_err; ++i) { dz[i] = h0 * K[i]; g1[i] -= K[i]; }
        double d2 = rms_pair(dz, g1, scale, ztmp, n_err) / h0;
        double dmax = d1 > d2 ? d1 : d2;
        double h1 = (dmax <= 1e-15) ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dmax, 1.0 / 12.0);
        h_abs = fmin(100.0 * h0, h1);
    }
    int rejected = 0;
    while (dn.k_out < nout) {
        if (t == t_end) { dense_emit(&dn, t_end); break; }
        if (n_acc + n_rej >= max_steps) { status = 1; break; }
        double min_step = 10.0 * fabs(nextafter(t, dir * INFINITY) - t);
        if (h_abs < min_step) { status = 2; break; }
        double h = h_abs * dir;
        double t_new = t + h;
        if (dir * (t_new - t_end) > 0) { t_new = t_end; h = t_new - t; h_abs = fabs(h); }
        double h2 = h * h;
        for (int s = 1; s < RKN_STAGES; ++s) {
            for (int i = 0; i < n2; ++i) {
                double acc = 0.0;
                for (int j = 0; j < s; ++j) acc += RKN_A[s][j] * K[(size_t)j * n2 + i];
                ztmp[i] = z[i] + RKN_C[s] * h * zd[i] + h2 * acc;
            }
            rhs(&cx, t + RKN_C[s] * h, ztmp, K + (size_t)s * n2);
        }
        if (cx.eph_error) { status = 4; break; }
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
            h_abs *= RKN_MIN_FACTOR; rejected = 1; ++n_rej; continue;
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
            rhs(&cx, t, z, K); /* the next step's first stage */
            if (cx.eph_error) { status = 4; break; }
            dense_add(&dn, t, z, zd, K);
            if (dn.count >= HERMITE_NODES) dense_emit(&dn, dn.t[(dn.count - 2) % HERMITE_NODES]);
            h_abs *= factor;
            rejected = 0;
            ++n_acc;
        } else {
            h_abs *= fmax(RKN_MIN_FACTOR, RKN_SAFETY * pow(err, RKN_ORDER_EXP));
            rejected = 1;
            ++n_rej;
        }
    }
    stats[0] = (double)n_acc; stats[1] = (double)n_rej; stats[2] = (double)cx.nfev;
    ctx_close(&cx);
    free(K); free(z); free(dn.node); free(dn.dd);
    return status;
}
