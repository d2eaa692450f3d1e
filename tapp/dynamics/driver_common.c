/*
 * Shared by the integrator drivers (dop853_driver.c, rkn12_driver.c): the call context of a
 * CasADi-generated right-hand side, the third-body (and iau2006 slow-term) Chebyshev table
 * evaluated before each call, the scaled RMS norm of step-size control, and the integration
 * events (tapp.dynamics.events): the boundaries where the force model is not smooth, located
 * so that no step straddles one.
 *
 * Third-body positions come from piecewise Chebyshev series (fitted to DE421 by
 * tapp.ephemeris) evaluated here, so the right-hand side stays a pure function.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The CasADi-generated functions, compiled apart and linked in (tapp.dynamics.compiled), with
 * the types its code generator is given there. */
#define casadi_real double
#define casadi_int long long int
#define GENERATED(name)                                                                     \
    int name(const casadi_real **arg, casadi_real **res, casadi_int *iw, casadi_real *w,     \
             int mem);                                                                      \
    int name##_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,              \
                    casadi_int *sz_w);
GENERATED(f_state)
GENERATED(f_var)
GENERATED(f_event)
#undef GENERATED

/* Entries of the series evaluated at a time: 3 per body or orientation series (at most 16). */
#define MAX_SERIES 48

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
    double rb[MAX_SERIES];
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
    long nfev;
    int eph_error;
} ctx_t;

/* Segment of the table and the Chebyshev variable tau in [-1, 1] at t (s); flags a time
 * outside the table in cx->eph_error. */
static int eph_segment(ctx_t *cx, double t, double *tau) {
    double u = (t - cx->eph_t0) / cx->eph_h;
    int seg = (int)floor(u);
    if (seg < 0 || seg >= cx->nseg) {
        /* allow the end point of the last segment and rounding at the first */
        if (seg == cx->nseg && u <= cx->nseg + 1e-9) seg = cx->nseg - 1;
        else if (seg == -1 && u >= -1e-9) seg = 0;
        else { cx->eph_error = 1; seg = seg < 0 ? 0 : cx->nseg - 1; }
    }
    *tau = 2.0 * (u - seg) - 1.0;
    return seg;
}

static const double *eph_coef(const ctx_t *cx, int b, int seg, int k) {
    return cx->eph + (((size_t)b * cx->nseg + seg) * 3 + k) * cx->ncoef;
}

/* Clenshaw's recurrence at tau for sum_j a_j T_j (rate = 0), or for its derivative
 * d/dtau = sum_{j>=1} j a_j U_{j-1}, a U series summed the same way (rate = 1). */
static double cheb_sum(const double *a, int ncoef, double tau, int rate) {
    double b1 = 0.0, b2 = 0.0;
    for (int j = ncoef - 1; j >= 1; --j) {
        double tmp = 2.0 * tau * b1 - b2 + (rate ? j * a[j] : a[j]);
        b2 = b1;
        b1 = tmp;
    }
    return rate ? b1 : tau * b1 - b2 + a[0];
}

static void eph_eval(ctx_t *cx, double t) {
    double tau;
    int seg = eph_segment(cx, t, &tau);
    for (int b = 0; b < cx->nb; ++b)
        for (int k = 0; k < 3; ++k)
            cx->rb[3 * b + k] = cheb_sum(eph_coef(cx, b, seg, k), cx->ncoef, tau, 0);
}

/* Rates (per s) of the series at t: the derivative in tau times dtau/dt = 2 / eph_h. */
static void eph_rate(ctx_t *cx, double t, double *rate) {
    double tau;
    int seg = eph_segment(cx, t, &tau);
    for (int b = 0; b < cx->nb; ++b)
        for (int k = 0; k < 3; ++k)
            rate[3 * b + k] = cheb_sum(eph_coef(cx, b, seg, k), cx->ncoef, tau, 1) * 2.0
                              / cx->eph_h;
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


/*
 * Integration events. Each event function g_i(r, v, rb, rbd) (the generated f_event, with its
 * rate dg/dt) is negative on one side of a boundary. At every step end the driver asks
 * ev_scan about the step [t0, t1], given (r, v, a) at both ends:
 *   - g_i changed sign: its root is located on the quintic Hermite polynomial through
 *     (r, v, a) at the two ends (Illinois' regula falsi to EVENT_TOL_S); where dg/dt changes
 *     sign towards and back away from zero with g_i on the same side, the extremum is found
 *     first (golden section) and a root searched before it, so that a step that enters and
 *     leaves a region is not missed;
 *   - a root within EVENT_TOL_S of t1 (or t0): the event is there (EV_AT_END, EV_AT_START):
 *     logged and its side flipped; the step is accepted;
 *   - a root inside the step: the step is discarded and the driver aims it anew at the root
 *     (EV_REAIM). The Hermite polynomial of a step that straddles a boundary is only
 *     approximate, but each aimed step ends nearer the root, where the polynomial is exact
 *     to third order in the distance from its end: one or two aimed steps locate it;
 *   - an aimed step that ended short of the root without crossing it: discarded too, and
 *     aimed anew at the Newton estimate t1 - g/(dg/dt) (EV_REAIM): accepting it would leave a
 *     last step of microseconds, which the rkn12 dense output cannot fit.
 * The location tolerance costs nothing in accuracy: the right-hand side is continuous at every
 * boundary (tapp.dynamics.events), so a step that straddles one by 1 us errs by far less than
 * a rounding error.
 */
#define EVENT_TOL_S 1e-6
#define EVENT_MAX_TRIES 16
enum { EV_NONE = 0, EV_AT_START, EV_AT_END, EV_REAIM };

typedef struct {
    int n;                                  /* event functions (0: none) */
    const casadi_real **arg;
    casadi_real **res;
    casadi_int *iw;
    casadi_real *w;
    double *g0, *gd0, *g1, *gd1, *gs, *gds; /* g, dg/dt at the step's start, end, scratch */
    signed char *side;                      /* side of each g the trajectory is on (+1, -1) */
    double rbd[MAX_SERIES];
    int cap, count;                         /* the log of located events */
    double *log_t;
    int *log_id;
    int *log_falling;
    int tries;                              /* aimed steps since the last event */
    int n_due;                              /* events of the step scanned last, at t_due */
    int *due;
    double t_due;
} events_t;

/* The quintic Hermite polynomial of a step through the position, velocity and acceleration
 * (3 components) at its two ends. */
typedef struct {
    double t0, h;
    double p0[3], v0[3], a0[3], p1[3], v1[3], a1[3];
} hermite_t;

static void hermite_set(hermite_t *hm, double t0, const double *p0, const double *v0,
                        const double *a0, double t1, const double *p1, const double *v1,
                        const double *a1) {
    hm->t0 = t0; hm->h = t1 - t0;
    for (int i = 0; i < 3; ++i) {
        hm->p0[i] = p0[i]; hm->v0[i] = v0[i]; hm->a0[i] = a0[i];
        hm->p1[i] = p1[i]; hm->v1[i] = v1[i]; hm->a1[i] = a1[i];
    }
}

/* Position and velocity at t (H0 = 1 - H3, so p = p0 + H3 (p1 - p0) + ...). */
static void hermite_eval(const hermite_t *hm, double t, double *p, double *v) {
    double h = hm->h, s = (t - hm->t0) / h;
    double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
    double H1 = s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5, H2 = 0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5);
    double H3 = 10.0 * s3 - 15.0 * s4 + 6.0 * s5, H4 = -4.0 * s3 + 7.0 * s4 - 3.0 * s5;
    double H5 = 0.5 * (s3 - 2.0 * s4 + s5);
    double D1 = 1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4, D2 = s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4;
    double D3 = 30.0 * s2 - 60.0 * s3 + 30.0 * s4, D4 = -12.0 * s2 + 28.0 * s3 - 15.0 * s4;
    double D5 = 1.5 * s2 - 4.0 * s3 + 2.5 * s4;
    for (int i = 0; i < 3; ++i) {
        double dp = hm->p1[i] - hm->p0[i];
        p[i] = hm->p0[i] + H3 * dp + h * (H1 * hm->v0[i] + H4 * hm->v1[i])
             + h * h * (H2 * hm->a0[i] + H5 * hm->a1[i]);
        v[i] = D3 * dp / h + D1 * hm->v0[i] + D4 * hm->v1[i] + h * (D2 * hm->a0[i] + D5 * hm->a1[i]);
    }
}

static void ev_open(events_t *ev, int n, int cap, double *log_t, int *log_id, int *log_falling) {
    memset(ev, 0, sizeof *ev);
    ev->n = n; ev->cap = cap; ev->log_t = log_t; ev->log_id = log_id;
    ev->log_falling = log_falling;
    if (n == 0) return;
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    f_event_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    ev->arg = malloc(sizeof(casadi_real *) * (sz_arg > 4 ? sz_arg : 4));
    ev->res = malloc(sizeof(casadi_real *) * (sz_res > 2 ? sz_res : 2));
    ev->iw = malloc(sizeof(casadi_int) * (sz_iw > 0 ? sz_iw : 1));
    ev->w = malloc(sizeof(casadi_real) * (sz_w > 0 ? sz_w : 1));
    ev->g0 = malloc(sizeof(double) * 6 * (size_t)n);
    ev->gd0 = ev->g0 + n; ev->g1 = ev->g0 + 2 * n; ev->gd1 = ev->g0 + 3 * n;
    ev->gs = ev->g0 + 4 * n; ev->gds = ev->g0 + 5 * n;
    ev->side = malloc((size_t)n);
    ev->due = malloc(sizeof(int) * (size_t)n);
}

static void ev_close(events_t *ev) {
    if (ev->n == 0) return;
    free(ev->arg); free(ev->res); free(ev->iw); free(ev->w); free(ev->g0); free(ev->side);
    free(ev->due);
}

/* g and dg/dt at (t, r, v), the bodies from the table at t. */
static void ev_eval(ctx_t *cx, events_t *ev, double t, const double *r, const double *v,
                    double *g, double *gd) {
    if (cx->nb > 0) { eph_eval(cx, t); eph_rate(cx, t, ev->rbd); }
    ev->arg[0] = r; ev->arg[1] = v; ev->arg[2] = cx->rb; ev->arg[3] = ev->rbd;
    ev->res[0] = g; ev->res[1] = gd;
    f_event(ev->arg, ev->res, ev->iw, ev->w, 0);
}

/* g_i (i >= 0) on the step's Hermite polynomial at t. */
static double ev_on_step(ctx_t *cx, events_t *ev, const hermite_t *hm, int i, double t) {
    double p[3], v[3];
    hermite_eval(hm, t, p, v);
    ev_eval(cx, ev, t, p, v, ev->gs, ev->gds);
    return ev->gs[i];
}

/* The sides at the start of the integration: where g = 0 exactly, the side it moves to. */
static void ev_start(ctx_t *cx, events_t *ev, double t, const double *r, const double *v,
                     double dir) {
    if (ev->n == 0) return;
    ev_eval(cx, ev, t, r, v, ev->g0, ev->gd0);
    for (int i = 0; i < ev->n; ++i) {
        double g = ev->g0[i] != 0.0 ? ev->g0[i] : ev->gd0[i] * dir;
        ev->side[i] = g >= 0.0 ? 1 : -1;
    }
}

/* Root of g_i on [ta, tb] (g_i on the side `side` at ta, across it at tb): Illinois. */
static double ev_root(ctx_t *cx, events_t *ev, const hermite_t *hm, int i, double ta,
                      double tb, double ga, double gb) {
    if (ga == 0.0 || (ga > 0.0) == (gb > 0.0)) return ta;  /* g is at its root at ta already */
    int last = 0;
    for (int it = 0; it < 200 && fabs(tb - ta) > 0.25 * EVENT_TOL_S; ++it) {
        double tc = tb - gb * (tb - ta) / (gb - ga);
        if (!(tc != ta && tc != tb && (tc - ta) * (tc - tb) < 0.0)) tc = 0.5 * (ta + tb);
        double gc = ev_on_step(cx, ev, hm, i, tc);
        if (gc == 0.0) return tc;
        if ((gc > 0.0) == (gb > 0.0)) {  /* root in [ta, tc] */
            tb = tc; gb = gc;
            if (last == -1) ga *= 0.5;
            last = -1;
        } else {
            ta = tc; ga = gc;
            if (last == 1) gb *= 0.5;
            last = 1;
        }
    }
    return fabs(ga) < fabs(gb) ? ta : tb;
}

/* Where side * g_i is least on [ta, tb] (golden section), and that value in *gmin. */
static double ev_extremum(ctx_t *cx, events_t *ev, const hermite_t *hm, int i, double ta,
                          double tb, double *gmin) {
    const double r = 0.6180339887498949;
    double s = ev->side[i];
    double x1 = tb - r * (tb - ta), x2 = ta + r * (tb - ta);
    double f1 = s * ev_on_step(cx, ev, hm, i, x1), f2 = s * ev_on_step(cx, ev, hm, i, x2);
    for (int it = 0; it < 80 && fabs(tb - ta) > EVENT_TOL_S; ++it) {
        if (f1 <= 0.0 || f2 <= 0.0) break;
        if (f1 < f2) { tb = x2; x2 = x1; f2 = f1; x1 = tb - r * (tb - ta); f1 = s * ev_on_step(cx, ev, hm, i, x1); }
        else { ta = x1; x1 = x2; f1 = f2; x2 = ta + r * (tb - ta); f2 = s * ev_on_step(cx, ev, hm, i, x2); }
    }
    if (f1 < f2) { *gmin = s * f1; return x1; }
    *gmin = s * f2;
    return x2;
}

/* Mark event i as met at t by the step scanned, for ev_accept. */
static void ev_due(events_t *ev, int i, double t) {
    ev->due[ev->n_due++] = i;
    ev->t_due = t;
}

/*
 * The events of the step hm = [t0, t1] in the direction dir (header above); `aimed_end`: the
 * step ended where the driver aimed it; `start_ok`: an event at t0 may be taken there (else
 * the driver is aimed at it: the rkn12 fit cannot end a piece at a step end it has passed).
 * Sets *t_aim for EV_REAIM. Returns -1 when the log is full. On EV_NONE, EV_AT_START and EV_AT_END the step is to be accepted and ev_accept
 * called.
 */
static int ev_scan(ctx_t *cx, events_t *ev, const hermite_t *hm, double dir, int aimed_end,
                   int start_ok, double *t_aim) {
    double t0 = hm->t0, t1 = hm->t0 + hm->h;
    ev->n_due = 0;
    ev_eval(cx, ev, t1, hm->p1, hm->v1, ev->g1, ev->gd1);
    for (int i = 0; i < ev->n; ++i)  /* a state the error test will reject anyway */
        if (!isfinite(ev->g1[i]) || !isfinite(ev->gd1[i])) return EV_NONE;
    int first = -1;
    double t_first = t1;
    for (int i = 0; i < ev->n; ++i) {
        double s = ev->side[i];
        double tb = t1, gb = ev->g1[i];
        if (s * gb >= 0.0) {
            /* Same side at both ends: a root pair only if g turns back within the step. */
            if (!(s * ev->gd0[i] * dir < 0.0 && s * ev->gd1[i] * dir > 0.0)) continue;
            tb = ev_extremum(cx, ev, hm, i, t0, t1, &gb);
            if (s * gb >= 0.0) continue;
        }
        double tr = ev_root(cx, ev, hm, i, t0, tb, ev->g0[i], gb);
        if (first < 0 || dir * (tr - t_first) < 0.0) { first = i; t_first = tr; }
    }
    if (first >= 0) {
        if (start_ok && fabs(t_first - t0) <= EVENT_TOL_S) {  /* and any other root as close */
            for (int i = 0; i < ev->n; ++i)
                if (i == first || (ev->side[i] * ev->g1[i] < 0.0 && fabs(ev_root(
                        cx, ev, hm, i, t0, t1, ev->g0[i], ev->g1[i]) - t0) <= EVENT_TOL_S))
                    ev_due(ev, i, t0);
            return EV_AT_START;
        }
        if (fabs(t1 - t_first) > EVENT_TOL_S) { *t_aim = t_first; return EV_REAIM; }
        for (int i = 0; i < ev->n; ++i)
            if (ev->side[i] * ev->g1[i] < 0.0) ev_due(ev, i, t1);
        return EV_AT_END;
    }
    if (!aimed_end) return EV_NONE;
    /* An aimed step short of its root: Newton from the end, for the functions heading there. */
    int ahead = -1;
    double t_ahead = 0.0;
    for (int i = 0; i < ev->n; ++i) {
        if (!(ev->side[i] * ev->gd1[i] * dir < 0.0)) continue;
        double tn = t1 - ev->g1[i] / ev->gd1[i];
        if (ahead < 0 || dir * (tn - t_ahead) < 0.0) { ahead = i; t_ahead = tn; }
    }
    if (ahead < 0 || fabs(t_ahead - t1) > fabs(hm->h)) return EV_NONE;
    if (fabs(t_ahead - t1) <= EVENT_TOL_S) { ev_due(ev, ahead, t1); return EV_AT_END; }
    *t_aim = t_ahead;
    return EV_REAIM;
}

/* The step scanned last is accepted: log its events and flip their sides (g went from + to
 * - in forward time when side * dir > 0); its end values become the next step's start.
 * Returns 0 when the log is full. */
static int ev_accept(events_t *ev, double dir) {
    for (int k = 0; k < ev->n_due; ++k) {
        int i = ev->due[k];
        if (ev->count >= ev->cap) return 0;
        ev->log_t[ev->count] = ev->t_due;
        ev->log_id[ev->count] = i;
        ev->log_falling[ev->count] = ev->side[i] * dir > 0.0;
        ev->count++;
        ev->side[i] = (signed char)-ev->side[i];
    }
    ev->n_due = 0;
    memcpy(ev->g0, ev->g1, sizeof(double) * 2 * (size_t)ev->n);  /* g0, gd0 <- g1, gd1 */
    return 1;
}
