/*
 * DOP853 (Dormand & Prince 8(5,3)) with 7th-order dense output, driving a CasADi-generated
 * right-hand side. Algorithm: Hairer, Norsett & Wanner, "Solving Ordinary Differential
 * Equations I", 2nd ed., Sec. II.5 and II.10; step-size control and dense output as in the
 * authors' DOP853 code. The Butcher tableau (DOP_C, DOP_A, DOP_B, DOP_E3, DOP_E5, DOP_D) is
 * emitted above this file by tapp.dynamics.compiled from SciPy's published copy of the same
 * coefficients, so no coefficient is typed by hand here.
 *
 * The right-hand-side context, the ephemeris evaluation and the norm come from
 * driver_common.c, emitted before this file.
 *
 * Return codes (documented in tapp.dynamics.compiled.STATUS):
 *   0 ok, 1 too many steps, 2 step size underflow, 3 non-finite state, 4 time outside the
 *   ephemeris table, 5 an event not located, 6 more events than the log holds.
 *
 * Events (driver_common.c): every accepted step is scanned for the event functions' roots on
 * the Hermite polynomial through (r, v, a) at its ends, y = (r, v, ...) and a = f[3:6]; a
 * step that straddles one is discarded and the next aimed at the root (clipped like the arc's
 * last step, the controller's step size kept for the steps after it), so every accepted
 * step integrates a smooth right-hand side. With no event functions the steps and results
 * are those of the driver without events, bit for bit.
 */
#define DOP_SAFETY 0.9
#define DOP_MIN_FACTOR 0.2
#define DOP_MAX_FACTOR 10.0
#define DOP_ORDER_EXP (-1.0 / 8.0)

/* Dense output: extra stages 13..15 and the 7 interpolation vectors F (scipy layout). */
static void dense_prepare(ctx_t *cx, int ny, double t_old, double h, const double *y_old,
                          const double *y_new, double *K, double *F, double *ytmp) {
    for (int s = 13; s < 16; ++s) {
        for (int i = 0; i < ny; ++i) {
            double acc = 0.0;
            for (int j = 0; j < s; ++j) acc += DOP_A[s][j] * K[(size_t)j * ny + i];
            ytmp[i] = y_old[i] + h * acc;
        }
        rhs(cx, t_old + DOP_C[s] * h, ytmp, K + (size_t)s * ny);
    }
    for (int i = 0; i < ny; ++i) {
        double f_old = K[i], f_new = K[(size_t)12 * ny + i];
        double dy = y_new[i] - y_old[i];
        F[i] = dy;
        F[(size_t)ny + i] = h * f_old - dy;
        F[(size_t)2 * ny + i] = 2.0 * dy - h * (f_new + f_old);
        for (int r = 0; r < 4; ++r) {
            double acc = 0.0;
            for (int j = 0; j < 16; ++j) acc += DOP_D[r][j] * K[(size_t)j * ny + i];
            F[(size_t)(3 + r) * ny + i] = h * acc;
        }
    }
}

static void dense_eval(int ny, double x, const double *y_old, const double *F, double *out) {
    for (int i = 0; i < ny; ++i) {
        double y = 0.0;
        for (int r = 6; r >= 0; --r) {
            y += F[(size_t)r * ny + i];
            y *= ((6 - r) % 2 == 0) ? x : (1.0 - x);
        }
        out[i] = y + y_old[i];
    }
}

/* The first step from (t, y), f0 = f(t, y): Hairer, Norsett & Wanner, Sec. II.4 (as in
 * DOP853's HINIT); f1, ytmp, scale, e3 are work arrays of ny. */
static double initial_step(ctx_t *cx, int ny, double t, const double *y, const double *f0,
                           double dir, double rtol, double atol, int n_err, double *f1,
                           double *ytmp, double *scale, double *e3) {
    for (int i = 0; i < n_err; ++i) scale[i] = atol + fabs(y[i]) * rtol;
    double d0 = rms_scaled(y, scale, n_err), d1 = rms_scaled(f0, scale, n_err);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    for (int i = 0; i < ny; ++i) ytmp[i] = y[i] + h0 * dir * f0[i];
    rhs(cx, t + h0 * dir, ytmp, f1);
    for (int i = 0; i < n_err; ++i) e3[i] = f1[i] - f0[i];
    double d2 = rms_scaled(e3, scale, n_err) / h0;
    double dmax = d1 > d2 ? d1 : d2;
    double h1 = (dmax <= 1e-15) ? fmax(1e-6, h0 * 1e-3) : pow(0.01 / dmax, 1.0 / 8.0);
    return fmin(100.0 * h0, h1);
}

/*
 * Integrate y' = f(t, y) from (t0, y0) through the monotonic output times tout[0..nout-1]
 * (either direction), writing y(tout[k]) to yout[k*ny ...]. Error control uses the first
 * n_err components. stats[0..3] = accepted steps, rejected steps, RHS evaluations, events
 * logged (their times, function indices and directions in ev_t, ev_id, ev_falling, at most
 * ev_cap).
 */
int tapp_integrate(int which, int ny, double t0, const double *y0, int nout, const double *tout,
                   double *yout, const double *q, const double *c, const double *eph, int nb,
                   int nseg, int ncoef, double eph_t0, double eph_h, double rtol, double atol,
                   int n_err, long max_steps, double *stats, int n_ev, int ev_cap, double *ev_t,
                   int *ev_id, int *ev_falling) {
    ctx_t cx;
    ctx_open(&cx, which, ny, q, c, eph, nb, nseg, ncoef, eph_t0, eph_h);
    events_t ev;
    ev_open(&ev, n_ev, ev_cap, ev_t, ev_id, ev_falling);
    double *K = malloc(sizeof(double) * 16 * (size_t)ny);
    double *F = malloc(sizeof(double) * 7 * (size_t)ny);
    double *y = malloc(sizeof(double) * (size_t)ny);
    double *y_new = malloc(sizeof(double) * (size_t)ny);
    double *ytmp = malloc(sizeof(double) * (size_t)ny);
    double *scale = malloc(sizeof(double) * (size_t)ny);
    double *e3 = malloc(sizeof(double) * (size_t)ny);
    double *e5 = malloc(sizeof(double) * (size_t)ny);
    int status = 0;
    long n_acc = 0, n_rej = 0;
    memcpy(y, y0, sizeof(double) * (size_t)ny);
    double t = t0;
    double t_end = tout[nout - 1];
    double dir = (t_end >= t0) ? 1.0 : -1.0;
    double t_stop = t_end;  /* the arc's end, or the root an event step is aimed at */
    int aimed = 0;
    int k_out = 0;
    while (k_out < nout && tout[k_out] == t0) {
        memcpy(yout + (size_t)k_out * ny, y, sizeof(double) * (size_t)ny);
        ++k_out;
    }
    double *f0 = K; /* K[0] holds f(t, y) at the start of every step */
    rhs(&cx, t, y, f0);
    ev_start(&cx, &ev, t, y, y + 3, dir);
    double h_abs = initial_step(&cx, ny, t, y, f0, dir, rtol, atol, n_err, K + (size_t)ny, ytmp,
                                scale, e3);
    int rejected = 0;
    while (k_out < nout) {
        if (n_acc + n_rej >= max_steps) { status = 1; break; }
        double min_step = 10.0 * fabs(nextafter(t, dir * INFINITY) - t);
        if (h_abs < min_step) { status = 2; break; }
        double h = h_abs * dir;
        double t_new = t + h;
        /* Clipped at the arc's end or at an aimed root; h_abs keeps the controller's size. */
        int clipped = dir * (t_new - t_stop) >= 0;
        if (clipped) { t_new = t_stop; h = t_new - t; }
        for (int s = 1; s < 12; ++s) {
            for (int i = 0; i < ny; ++i) {
                double acc = 0.0;
                for (int j = 0; j < s; ++j) acc += DOP_A[s][j] * K[(size_t)j * ny + i];
                ytmp[i] = y[i] + h * acc;
            }
            rhs(&cx, t + DOP_C[s] * h, ytmp, K + (size_t)s * ny);
        }
        for (int i = 0; i < ny; ++i) {
            double acc = 0.0;
            for (int j = 0; j < 12; ++j) acc += DOP_B[j] * K[(size_t)j * ny + i];
            y_new[i] = y[i] + h * acc;
        }
        rhs(&cx, t_new, y_new, K + (size_t)12 * ny);
        if (cx.eph_error) { status = 4; break; }
        double s5 = 0.0, s3 = 0.0;
        for (int i = 0; i < n_err; ++i) {
            double sc = atol + rtol * fmax(fabs(y[i]), fabs(y_new[i]));
            double a5 = 0.0, a3 = 0.0;
            for (int j = 0; j < 13; ++j) {
                a5 += DOP_E5[j] * K[(size_t)j * ny + i];
                a3 += DOP_E3[j] * K[(size_t)j * ny + i];
            }
            a5 /= sc; a3 /= sc;
            s5 += a5 * a5; s3 += a3 * a3;
        }
        double err = 0.0;
        double h_step = fabs(h);
        if (s5 > 0.0 || s3 > 0.0) err = h_step * s5 / sqrt((s5 + 0.01 * s3) * n_err);
        if (!isfinite(err)) {
            h_abs = h_step * DOP_MIN_FACTOR; rejected = 1; ++n_rej; continue;
        }
        int event = EV_NONE;
        if (ev.n > 0) {
            hermite_t hm;
            const double *f_new = K + (size_t)12 * ny;
            double t_aim = t_stop;
            hermite_set(&hm, t, y, y + 3, f0 + 3, t_new, y_new, y_new + 3, f_new + 3);
            event = ev_scan(&cx, &ev, &hm, dir, aimed && clipped, 1, &t_aim);
            if (cx.eph_error) { status = 4; break; }
            if (event == EV_REAIM) {
                if (++ev.tries > EVENT_MAX_TRIES) { status = 5; break; }
                t_stop = t_aim; aimed = 1; ++n_rej; continue;
            }
        }
        if (err < 1.0) {
            double factor = (err == 0.0) ? DOP_MAX_FACTOR
                                         : fmin(DOP_MAX_FACTOR, DOP_SAFETY * pow(err, DOP_ORDER_EXP));
            if (rejected && factor > 1.0) factor = 1.0;
            int prepared = 0;
            while (k_out < nout && dir * (tout[k_out] - t_new) <= 0) {
                if (tout[k_out] == t_new) {
                    memcpy(yout + (size_t)k_out * ny, y_new, sizeof(double) * (size_t)ny);
                } else {
                    if (!prepared) { dense_prepare(&cx, ny, t, h, y, y_new, K, F, ytmp); prepared = 1; }
                    dense_eval(ny, (tout[k_out] - t) / h, y, F, yout + (size_t)k_out * ny);
                }
                ++k_out;
            }
            if (cx.eph_error) { status = 4; break; }
            t = t_new;
            memcpy(y, y_new, sizeof(double) * (size_t)ny);
            memcpy(K, K + (size_t)12 * ny, sizeof(double) * (size_t)ny);
            if (!clipped) h_abs *= factor;
            rejected = 0;
            ++n_acc;
            if (ev.n > 0) {
                if (!ev_accept(&ev, dir)) { status = 6; break; }
                if (aimed && (clipped || event != EV_NONE)) {
                    t_stop = t_end; aimed = 0; ev.tries = 0;
                }
                if (event == EV_AT_END)  /* a new start, where f is not smooth */
                    h_abs = fmin(h_abs, initial_step(&cx, ny, t, y, K, dir, rtol, atol, n_err,
                                                     K + (size_t)ny, ytmp, scale, e3));
            }
            int finite = 1;
            for (int i = 0; i < ny; ++i) if (!isfinite(y[i])) { finite = 0; break; }
            if (!finite) { status = 3; break; }
        } else {
            h_abs = h_step * fmax(DOP_MIN_FACTOR, DOP_SAFETY * pow(err, DOP_ORDER_EXP));
            rejected = 1;
            ++n_rej;
        }
    }
    stats[0] = (double)n_acc; stats[1] = (double)n_rej; stats[2] = (double)cx.nfev;
    stats[3] = (double)ev.count;
    ctx_close(&cx);
    ev_close(&ev);
    free(K); free(F); free(y); free(y_new); free(ytmp); free(scale); free(e3); free(e5);
    return status;
}
