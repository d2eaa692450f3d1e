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
 * (Hairer, Norsett & Wanner I, Sec. II.4), exponent 1/11; the first step from the time scale
 * of the motion. The first stage of a step is the
 * acceleration at its start, so it is taken from the previous step (17 evaluations a step,
 * one of them at the step's end).
 *
 * Dense output: the pair has no continuous extension, so outputs come from the confluent
 * Hermite polynomial through (z, z', z'') at `nodes` consecutive step ends (degree
 * 3 nodes - 1; Hairer, Norsett & Wanner I, Sec. II.6; confluent divided differences as in
 * Stoer & Bulirsch, Sec. 2.1.5, one new row of differences a step), evaluated in Newton form
 * by Horner's rule, outputs side by side; z' at an output is the derivative of that
 * polynomial. An output in step j, [t_j, t_{j+1}], uses the step ends centred on it
 * (j - nodes/2 + 1 .. j + nodes/2, clamped at the two ends of the arc), so it is written
 * nodes/2 steps late; the arc's last steps are shortened to keep the one-sided fit there
 * accurate. Measured on a LEO day at 1e-12 against heyoka at machine precision: four step
 * ends left 0.2 mm between steps (the step error is 0.01-0.02 mm); six leave the state within
 * the step error for J2 and 0.026 mm (step error 0.015 mm) for 5x5, at 35% less output cost
 * than eight; Φ needs eight (six left 1e-10 relative early in the arc, where Φ is small;
 * eight leave 3e-12, the step error).
 *
 * Events (driver_common.c) as in the DOP853 driver, on the Hermite polynomial through
 * (z, z', z'')[0:3] = (r, v, a) at the step's ends: a step aimed at a root is shortened like
 * the arc's last steps, and at the event the outputs up to it are written from the fit ending
 * there and the fit starts anew (a fit across the event would smooth the kink: 176 m inside
 * eclipses), with the first step of the new piece chosen like the arc's first. A stop
 * (event or arc's end) that would leave a last step shorter than DENSE_MIN_GAP of the one
 * before drops that step end and splits the stretch anew from the one before it.
 *
 * Return codes as the DOP853 driver (tapp.dynamics.compiled.STATUS).
 */
#define RKN_STAGES 17
#define RKN_SAFETY 0.9
#define RKN_MIN_FACTOR 0.2
#define RKN_MAX_FACTOR 5.0
#define RKN_ORDER_EXP (-1.0 / 11.0)
/* Step ends of the Hermite fit: NODES_STATE for the state alone, NODES_VAR with Φ and S
 * (see the header), at most MAX_NODES. An output in step j is written once step end
 * j + nodes / 2 is known. */
#define NODES_STATE 6
#define NODES_VAR 8
#define MAX_NODES 8
#define MAX_DD (3 * MAX_NODES)
/* Ring buffer of step ends: a power of two > MAX_NODES, so that a slot is a mask and the
 * fit can drop its newest step end and be rebuilt from the ones before (dense_pop). */
#define RING 16
#define SLOT(m) ((size_t)(m) & (RING - 1))
/* A step shorter than this fraction of the last one is not taken: the last step end is
 * dropped and the stretch to the stop (an event or the arc's end) is split anew from the
 * one before (dense_pop). Divided differences across a short gap after long ones amplify
 * rounding by about (h / gap)^5, and a fit ended early instead (at the last step end) is
 * one-sided over full steps: 0.5 m off on a LEO at 1e-11. */
#define DENSE_MIN_GAP 0.25
/* Outputs evaluated side by side (Horner is latency-bound for one output). */
#define DENSE_BATCH 16
/* Inlined into each caller, so that the state case (n2 = 3) is compiled with n2 constant. */
#define INLINE static inline __attribute__((always_inline))

/* The step ends of the current piece (the last RING of them; a fit uses the last `nodes`),
 * the divided differences ending at the last one, and the outputs still to write. A piece
 * ends at an event: the next one starts at its last step end. */
typedef struct {
    int nodes;                 /* step ends in a fit */
    long count;                /* step ends received so far */
    long base;                 /* index of the first step end of the current piece */
    double t[RING];
    double *node;              /* RING x (z, z', z''), each n2 */
    double *dd;                /* MAX_DD x n2: f[y_{J-k}, .., y_J], k = 0 .. */
    int n_dd;                  /* rows of dd in use: 3 min(count - base, nodes) */
    int nout;
    const double *tout;
    double *yout;
    int k_out;                 /* next output to write */
    double dir;
} dense_t;

INLINE double *node_slot(const dense_t *d, long m, int n2) {
    return d->node + SLOT(m) * 3 * n2;
}

/* Step ends in the fit that ends at the last one. */
INLINE int dense_width(const dense_t *d) {
    long w = d->count - d->base;
    return w < d->nodes ? (int)w : d->nodes;
}

/* Append step end m (in its slot), thrice (z, then z' and z''/2 as the confluent
 * differences), as the w-th point of the fit, to the points y_0, y_1, ... (times in s), and
 * update the last row of the divided-difference table, dd[k] = f[y_{J-k}, .., y_J], in place
 * (Stoer & Bulirsch, Sec. 2.1.5): only the differences over the last `nodes` step ends are
 * kept. */
INLINE void dense_update(dense_t *d, long m, int w, int n2) {
    const double *z = node_slot(d, m, n2), *zd = z + n2, *zdd = z + 2 * n2;
    double t = d->t[SLOT(m)];
    double inv[MAX_DD];
    for (int copy = 0; copy < 3; ++copy) {
        int n = 3 * (w - 1) + copy + 1;  /* rows after this append */
        for (int k = copy + 1; k < n; ++k)  /* y_J - y_{J-k}: another step end */
            inv[k] = 1.0 / (t - d->t[SLOT(m - (k - copy + 2) / 3)]);
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

/* Append a step end (t, z, z', z''). */
INLINE void dense_add(dense_t *d, double t, const double *z, const double *zd,
                      const double *zdd, int n2) {
    double *slot = node_slot(d, d->count, n2);
    d->t[SLOT(d->count)] = t;
    memcpy(slot, z, sizeof(double) * (size_t)n2);
    memcpy(slot + n2, zd, sizeof(double) * (size_t)n2);
    memcpy(slot + 2 * n2, zdd, sizeof(double) * (size_t)n2);
    d->count++;
    dense_update(d, d->count - 1, dense_width(d), n2);
}

/* Rebuild the table of the fit ending at the last step end. */
INLINE void dense_rebuild(dense_t *d, int n2) {
    int w = dense_width(d);
    for (int j = 0; j < w; ++j) dense_update(d, d->count - w + j, j + 1, n2);
}

/* Drop the newest step end (at least one stays in the piece). */
INLINE void dense_pop(dense_t *d, int n2) {
    d->count--;
    dense_rebuild(d, n2);
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
    int w = dense_width(d), nb = 0;
    double tb[MAX_NODES], ts[DENSE_BATCH];
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

/* The first step from (z, z', z'') at the start of a piece: a tenth of the motion's time scale
 * min(sqrt(|z| / |z''|), |z| / |z'|) (about 1/n on an orbit; norms over the error-controlled
 * components), at most h_max. The generic estimate of Hairer, Norsett & Wanner (Sec. II.4)
 * starts a LEO at 0.06 s and takes 8 steps to grow to the 500 s a step holds; the short steps
 * also bunch the first step ends of the dense output. */
INLINE double first_step(const double *z, const double *zd, const double *zdd, int n_err,
                         double h_max) {
    double h_abs = h_max, r2 = 0.0, v2 = 0.0, a2 = 0.0;
    for (int i = 0; i < n_err; ++i) { r2 += z[i] * z[i]; v2 += zd[i] * zd[i]; a2 += zdd[i] * zdd[i]; }
    if (a2 > 0.0) h_abs = fmin(h_abs, 0.1 * pow(r2 / a2, 0.25));
    if (v2 > 0.0) h_abs = fmin(h_abs, 0.1 * sqrt(r2 / v2));
    return h_abs;
}

/* Write the outputs up to the last step end and start a new piece there: an event ends a
 * piece of the dense output. */
INLINE void dense_restart(dense_t *d, int n2) {
    dense_emit(d, d->t[SLOT(d->count - 1)], n2);
    d->base = d->count - 1;
    dense_rebuild(d, n2);
}

/* The integration of tapp_integrate for n2 components (a constant where inlined). */
INLINE int rkn_run(ctx_t *cx, events_t *ev, int n2, double t0, const double *y0, dense_t *dn,
                   double rtol, double atol, int n_err, long max_steps, double *work,
                   long *n_acc, long *n_rej) {
    double *K = work;
    double *z = work + RKN_STAGES * (size_t)n2;
    double *zd = z + n2, *z_new = z + 2 * n2, *zd_new = z + 3 * n2, *ztmp = z + 4 * n2;
    double *scale = z + 5 * n2;
    double *a_new = z + 6 * n2;  /* the acceleration at the step's end: the next first stage */
    int status = 0;
    memcpy(z, y0, sizeof(double) * 2 * (size_t)n2);
    double t = t0;
    double t_end = dn->tout[dn->nout - 1];
    double dir = dn->dir;
    double t_stop = t_end;  /* the arc's end, or the root an event step is aimed at */
    int aimed = 0;
    rhs(cx, t, z, K);
    dense_add(dn, t, z, zd, K, n2);
    dense_emit(dn, t0, n2);
    ev_start(cx, ev, t, z, zd, dir);
    /* h_ctrl: the step the controller proposes; a step is shorter only to end at a stop. */
    double h_ctrl = first_step(z, zd, K, n_err, fabs(t_end - t0));
    int rejected = 0;
    while (dn->k_out < dn->nout) {
        if (t == t_end) { dense_emit(dn, t_end, n2); break; }
        if (*n_acc + *n_rej >= max_steps) { status = 1; break; }
        double min_step = 10.0 * fabs(nextafter(t, dir * INFINITY) - t);
        if (h_ctrl < min_step) { status = 2; break; }
        /* The last steps before the arc's end or an event shrink (to at most half a step):
         * the outputs there come from the Hermite fit at the edge of its window, whose error
         * grows fast with the length of the edge steps. */
        double left = fabs(t_stop - t), h_abs = h_ctrl;
        int last = left <= 0.5 * h_ctrl;
        if (last) h_abs = left;
        else if (left <= 2.0 * h_ctrl) h_abs = 0.5 * left;
        /* A stop just after the last step end: split the stretch from the one before. */
        if (h_abs < h_ctrl && dn->count - dn->base >= 2 &&
            h_abs < DENSE_MIN_GAP * fabs(t - dn->t[SLOT(dn->count - 2)])) {
            dense_pop(dn, n2);
            const double *node = node_slot(dn, dn->count - 1, n2);
            t = dn->t[SLOT(dn->count - 1)];
            memcpy(z, node, sizeof(double) * 2 * (size_t)n2);
            memcpy(K, node + 2 * n2, sizeof(double) * (size_t)n2);
            if (ev->n > 0) ev_eval(cx, ev, t, z, zd, ev->g0, ev->gd0);
            continue;
        }
        if (h_abs < min_step) { status = 2; break; }
        double h = h_abs * dir;
        double t_new = last ? t_stop : t + h;
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
            h_ctrl = h_abs * RKN_MIN_FACTOR; rejected = 1; ++*n_rej; continue;
        }
        int event = EV_NONE;
        if (ev->n > 0) {  /* scanned before the error test (ev_scan) */
            rhs(cx, t_new, z_new, a_new);
            if (cx->eph_error) { status = 4; break; }
            hermite_t hm;
            double t_aim = t_stop;
            hermite_set(&hm, t, z, zd, K, t_new, z_new, zd_new, a_new);
            event = ev_scan(cx, ev, &hm, dir, aimed && last, dn->count - dn->base < 2, &t_aim);
            if (cx->eph_error) { status = 4; break; }
            if (event == EV_REAIM) {
                if (++ev->tries > EVENT_MAX_TRIES) { status = 5; break; }
                t_stop = t_aim; aimed = 1; ++*n_rej; continue;
            }
        }
        if (err < 1.0) {
            double factor = (err == 0.0) ? RKN_MAX_FACTOR
                                         : fmin(RKN_MAX_FACTOR, RKN_SAFETY * pow(err, RKN_ORDER_EXP));
            if (rejected && factor > 1.0) factor = 1.0;
            int finite = 1;
            for (int i = 0; i < 2 * n2; ++i) if (!isfinite(z_new[i])) { finite = 0; break; }
            if (!finite) { status = 3; break; }
            if (ev->n == 0) {
                rhs(cx, t_new, z_new, a_new);
                if (cx->eph_error) { status = 4; break; }
            }
            if (event == EV_AT_START) dense_restart(dn, n2);
            t = t_new;
            memcpy(z, z_new, sizeof(double) * 2 * (size_t)n2);
            memcpy(K, a_new, sizeof(double) * (size_t)n2);  /* the next step's first stage */
            dense_add(dn, t, z, zd, K, n2);
            if (h_abs == h_ctrl) h_ctrl *= factor;
            rejected = 0;
            ++*n_acc;
            if (ev->n > 0 && !ev_accept(ev, dir)) { status = 6; break; }
            if (event == EV_AT_END) {
                dense_restart(dn, n2);
                h_ctrl = first_step(z, zd, K, n_err, h_ctrl);
                t_stop = t_end; aimed = 0; ev->tries = 0;
                continue;
            }
            if (aimed && last) { t_stop = t_end; aimed = 0; ev->tries = 0; }
            if (dn->count - dn->base >= dn->nodes)
                dense_emit(dn, dn->t[SLOT(dn->count - dn->nodes / 2)], n2);
        } else {
            h_ctrl = h_abs * fmax(RKN_MIN_FACTOR, RKN_SAFETY * pow(err, RKN_ORDER_EXP));
            rejected = 1;
            ++*n_rej;
        }
    }
    return status;
}

/*
 * Integrate z'' = g(t, z) from (t0, [z0, z0']) through the monotonic output times
 * tout[0..nout-1] (either direction), writing [z, z'](tout[k]) to yout[k*ny ...].
 * stats[0..3] = accepted steps, rejected steps, RHS evaluations, events logged (as in the
 * DOP853 driver).
 */
int tapp_integrate(int which, int ny, double t0, const double *y0, int nout, const double *tout,
                   double *yout, const double *q, const double *c, const double *eph, int nb,
                   int nseg, int ncoef, double eph_t0, double eph_h, double rtol, double atol,
                   int n_err, long max_steps, double *stats, int n_ev, int ev_cap, double *ev_t,
                   int *ev_id, int *ev_falling) {
    int n2 = ny / 2;
    ctx_t cx;
    ctx_open(&cx, which, n2, q, c, eph, nb, nseg, ncoef, eph_t0, eph_h);
    events_t ev;
    ev_open(&ev, n_ev, ev_cap, ev_t, ev_id, ev_falling);
    double *work = malloc(sizeof(double) * (RKN_STAGES + 7) * (size_t)n2);
    dense_t dn = {which == 0 ? NODES_STATE : NODES_VAR, 0, 0, {0},
                  malloc(sizeof(double) * RING * 3 * (size_t)n2),
                  malloc(sizeof(double) * MAX_DD * (size_t)n2), 0, nout, tout, yout, 0,
                  (tout[nout - 1] >= t0) ? 1.0 : -1.0};
    long n_acc = 0, n_rej = 0;
    int status = n2 == 3
        ? rkn_run(&cx, &ev, 3, t0, y0, &dn, rtol, atol, n_err, max_steps, work, &n_acc, &n_rej)
        : rkn_run(&cx, &ev, n2, t0, y0, &dn, rtol, atol, n_err, max_steps, work, &n_acc, &n_rej);
    stats[0] = (double)n_acc; stats[1] = (double)n_rej; stats[2] = (double)cx.nfev;
    stats[3] = (double)ev.count;
    ctx_close(&cx);
    ev_close(&ev);
    free(work); free(dn.node); free(dn.dd);
    return status;
}
