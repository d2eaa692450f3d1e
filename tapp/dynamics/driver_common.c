/*
 * Shared by the integrator drivers (dop853_driver.c, rkn12_driver.c): the call context of a
 * CasADi-generated right-hand side, the third-body (and iau2006 slow-term) Chebyshev table
 * evaluated before each call, and the scaled RMS norm of step-size control.
 *
 * Third-body positions come from piecewise Chebyshev series (fitted to DE421 by
 * tapp.ephemeris) evaluated here, so the right-hand side stays a pure function.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef int (*rhs_fn)(const casadi_real **arg, casadi_real **res, casadi_int *iw,
                      casadi_real *w, int mem);

typedef struct {
    rhs_fn f;
    int ny;
    casadi_real t_buf;
    const double *q, *c;
    const double *eph;
    int nb, nseg, ncoef;
    double eph_t0, eph_h;
    double rb[3 * 16];
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
    long nfev;
    int eph_error;
} ctx_t;

static void eph_eval(ctx_t *cx, double t) {
    double u = (t - cx->eph_t0) / cx->eph_h;
    int seg = (int)floor(u);
    if (seg < 0 || seg >= cx->nseg) {
        /* allow the end point of the last segment and rounding at the first */
        if (seg == cx->nseg && u <= cx->nseg + 1e-9) seg = cx->nseg - 1;
        else if (seg == -1 && u >= -1e-9) seg = 0;
        else { cx->eph_error = 1; seg = seg < 0 ? 0 : cx->nseg - 1; }
    }
    double tau = 2.0 * (u - seg) - 1.0;
    for (int b = 0; b < cx->nb; ++b) {
        for (int k = 0; k < 3; ++k) {
            const double *a = cx->eph + (((size_t)b * cx->nseg + seg) * 3 + k) * cx->ncoef;
            double b1 = 0.0, b2 = 0.0;
            for (int j = cx->ncoef - 1; j >= 1; --j) {
                double tmp = 2.0 * tau * b1 - b2 + a[j];
                b2 = b1;
                b1 = tmp;
            }
            cx->rb[3 * b + k] = tau * b1 - b2 + a[0];
        }
    }
}

static void rhs(ctx_t *cx, double t, const double *y, double *dy) {
    if (cx->nb > 0) eph_eval(cx, t);
    cx->t_buf = t;
    cx->arg[0] = &cx->t_buf;
    cx->arg[1] = y;
    cx->arg[2] = cx->q;
    cx->arg[3] = cx->c;
    cx->arg[4] = cx->rb;
    cx->res[0] = dy;
    cx->f(cx->arg, cx->res, cx->iw, cx->w, 0);
    cx->nfev++;
}

static double rms_scaled(const double *v, const double *scale, int n) {
    double s = 0.0;
    for (int i = 0; i < n; ++i) { double e = v[i] / scale[i]; s += e * e; }
    return sqrt(s / n);
}


/* Point the context at f_state (which = 0) or f_var (which = 1) and allocate its work arrays. */
static void ctx_open(ctx_t *cx, int which, int ny, const double *q, const double *c,
                     const double *eph, int nb, int nseg, int ncoef, double eph_t0,
                     double eph_h) {
    memset(cx, 0, sizeof *cx);
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    if (which == 0) { cx->f = f_state; f_state_work(&sz_arg, &sz_res, &sz_iw, &sz_w); }
    else { cx->f = f_var; f_var_work(&sz_arg, &sz_res, &sz_iw, &sz_w); }
    cx->ny = ny; cx->q = q; cx->c = c; cx->eph = eph; cx->nb = nb; cx->nseg = nseg;
    cx->ncoef = ncoef; cx->eph_t0 = eph_t0; cx->eph_h = eph_h;
    cx->arg = malloc(sizeof(casadi_real *) * (sz_arg > 5 ? sz_arg : 5));
    cx->res = malloc(sizeof(casadi_real *) * (sz_res > 1 ? sz_res : 1));
    cx->iw = malloc(sizeof(casadi_int) * (sz_iw > 0 ? sz_iw : 1));
    cx->w = malloc(sizeof(casadi_real) * (sz_w > 0 ? sz_w : 1));
}

static void ctx_close(ctx_t *cx) {
    free(cx->arg); free(cx->res); free(cx->iw); free(cx->w);
}
