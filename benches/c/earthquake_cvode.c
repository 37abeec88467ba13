/* Plain-C reference for the earthquake benchmark (benches/earthquake.rs).
 *
 * Integrates the earthquake scene (data/scenes/earthquake.json: γ = 1e8, ξ = 0.8, ε = 1,
 * f = ln v, slip law, η = 0) in y = (u, w = ln v, θ) with CVODE exactly as stickslip's safe
 * wrapper does (src/sundials/solver.rs, cvode.rs, callbacks.rs) with the engine's options
 * (engine::integrator_for): CVodeCreate(CV_BDF), CVodeInit, an error handler that records
 * messages instead of printing them, CVodeSetMaxHnilWarns(INT_MAX), CVodeWFtolerances with
 * the engine's error weights (rtol 1e-10, atol 1e-12 per component; u and θ weighed relative to
 * their size, ln v absolutely at rtol/10: Options::error_scales), at most 1e6 steps per call,
 * at most 20 convergence failures per step, the engine's max step (1/8 of
 * the linear period, given on the command line), at most 20 error-test failures per step,
 * dense matrix + dense linear solver, analytic Jacobian, a linear-solver setup and Jacobian at
 * every step, CVODE defaults otherwise. The RHS and Jacobian are the formulas of
 * src/model/drr.rs written in the same order of operations (du/dt = expm1(w), the arrest rate
 * held below ln v = −500); they return +1 (recoverable) on non-finite values as the wrapper's
 * trampolines do, and the RHS refuses (−1) after a "t + h = t" warning in the same CVode call
 * (the wrapper's fail_on_step_underflow).
 *
 * It replicates the time bookkeeping (src/integrate/clock.rs) and the cycle engine
 * (src/analysis/cycle.rs, events.rs) step for step:
 * - the Clock: CV_ONE_STEP calls with tout = (local t) + 1e6 on a local clock; before a step,
 *   if the last step fell below RESTART_THRESHOLD = 1e4 ulps of the local time, a re-base
 *   (CVodeReInit at (0, state) with CVodeSetInitStep(last step); the next reinit restores the
 *   configured initial step, as Solver::reinit does); on a "t + h = t" inside a call away from
 *   local t = 0, a re-base with CVODE's current step and one more try; the global time of the
 *   local origin kept as a double-double (Time::plus / since, two-sum in the same order);
 * - after each step CVodeGetDky(t, 1) at the step end; events between step ends (sign
 *   changes of w, of the interpolant's dw/dt, du/dt, dθ/dt, and the fall through half the
 *   maximum), each refined by the same Illinois iteration on CVodeGetDky and evaluated with
 *   CVodeGetDky(t, 0); every duration a difference of global times (Time::since);
 * - the same rise buffer (kept across a wiggle in the rise), cubic-Hermite half-maximum
 *   crossing (the last one before the peak) and half-maximum fall inside the peak's step;
 * - the same restart policy: no re-base at the slip peak (the engine re-bases there only
 *   integrators whose re-base is an exact time shift, never CVODE), and one in the rise when
 *   the clock is too coarse (γ·t > 1/(1e3 ε) at the upward crossing of v = 1; never in this
 *   scene), at a point where the model's dw/dt is resolved (restart_safe);
 * - EscapeStep (given on the command line, as engine::cycle_with sets it): the steps limited
 *   while the state rests within the integration noise of the unstable fixed point (never in
 *   this scene).
 * Not replicated: the engine's convergence rule (a few comparisons per closed cycle), replaced
 * by "stop after N closed cycles" (the engine stops after 5 cycles on this scene, so both
 * integrate exactly the same steps); the fixed-point test, which runs only at a linearly
 * stable fixed point (this scene's is unstable); deep sticks crossed in closed form below
 * ln v = −500 (the program fails there; ln v stays above −4 here).
 *
 * Usage:
 *   earthquake_cvode R [N [MAX_STEP ESCAPE_NEAR]]
 *                                 R runs of N cycles (default 5) after WARMUP untimed runs;
 *                                 prints "elapsed_ns X", "steps S" (total over the R runs)
 *                                 and "period P" (last cycle of the last run, %.17e)
 *   earthquake_cvode R each [N [MAX_STEP ESCAPE_NEAR]]
 *                                 times R runs individually (after EACH_WARMUP untimed runs)
 *                                 and prints each run's nanoseconds on its own line
 *   earthquake_cvode check [N [MAX_STEP ESCAPE_NEAR]]
 *                                 one run; prints every cycle (steps, period, ...), the
 *                                 re-bases, retries and escapes, and the CVODE counters summed
 *                                 over restarts
 *     MAX_STEP: the engine's max step; ESCAPE_NEAR: EscapeStep::near (its `elsewhere` is
 *     MAX_STEP); both 0 (none) when left out.
 *   earthquake_cvode wp GAMMA RTOL ATOL MAX_STEP U0 W0 THETA0 N RUNS BUDGET_S
 *                                 the work-precision benchmark (benches/work_precision): the
 *                                 same engine at another γ, tolerance and start, with the
 *                                 engine's max step and no EscapeStep (as its Rust side,
 *                                 protocol::run_ours, runs the cycle analysis); prints one
 *                                 JSON line (see work_precision() below)
 * Exit status 1 if a SUNDIALS call fails or a "t + h = t" persists after the retry (the
 * wrapper fails then too), 64 on bad usage.
 */
#define _POSIX_C_SOURCE 199309L

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define NEQ 3
#define U 0
#define W 1
#define TH 2
#define XI 0.8
#define EPS 1.0
#define V0 0.45
/* The earthquake scene's γ, tolerances and start; the work-precision mode ("wp") sets them
 * from its arguments. */
static double GAMMA = 1.0e8;
static double RTOL = 1.0e-10;
static double ATOL = 1.0e-12;
static double U0 = 1.0;
static double THETA0 = 0.0;
static int w0_given = 0; /* 0: w0 = log(V0) computed at run time; 1: W0 */
static double W0;
static double MAX_STEP = 0.0;    /* the engine's max step; 0: none (CVODE's default) */
static double ESCAPE_NEAR = 0.0; /* EscapeStep::near; 0: no EscapeStep (as in "wp") */
/* CycleSettings::defaults(1e-10) */
#define MAX_TIME 1.0e6
#define MAX_STEPS 20000000L
#define MAX_CYCLES 64
#define LN_2 0.693147180559945309417232121458176568
#define WARMUP 1
#define EACH_WARMUP 3

static double GAMMA2 = 1.0e8 * 1.0e8; /* GAMMA * GAMMA, reset by "wp" */

/* ------------------------------------------------------------------ model (drr.rs) */

/* drr::ARREST_RATE_HELD_BELOW: below this ln v the arrest rate γ²e^(−w) is held (log friction) */
#define ARREST_RATE_HELD_BELOW (-500.0)

static int all_finite(const double *v, int n) {
  int i;
  for (i = 0; i < n; i++)
    if (!isfinite(v[i])) return 0;
  return 1;
}

/* Drr::arrest_rate: γ²e^(−w), held below ARREST_RATE_HELD_BELOW; *varies: whether it depends on
 * w there. */
static double arrest_rate(double w, int *varies) {
  if (w > ARREST_RATE_HELD_BELOW) {
    *varies = 1;
    return GAMMA2 * exp(-w);
  }
  *varies = 0;
  return GAMMA2 * exp(-ARREST_RATE_HELD_BELOW);
}

/* Drr::split (OdeSystem::rhs) for Friction::Log (f = w, v f' = 1), the slip law (F(x) = −x:
 * LawTerms f = −v x) and η = 0, in the same order of operations. */
static void model_rhs(const double *y, double *d) {
  int varies;
  double w = y[W];
  double g = y[U] + (y[TH] + w) / XI;         /* manifold_offset: resistance value f = w */
  double dw = -arrest_rate(w, &varies) * g;
  double x = y[TH] / (1.0 + EPS) + w;         /* law_argument */
  double v = exp(w);
  double dtheta = (1.0 + EPS) * (-v * x);     /* (1+ε) StateLaw::Slip.rate(w, v, x) */
  d[U] = expm1(w);
  d[W] = dw;
  d[TH] = dtheta;
}

/* The wrapper's diagnostics (src/sundials/callbacks.rs): "t + h = t" warnings and non-finite
 * right-hand sides, counted over the solver's life and per CVode call; with
 * fail_on_step_underflow (the engine's default) the first right-hand-side call after a
 * "t + h = t" warning in a call refuses (-1), so CVODE returns at once. */
static long step_underflows, nonfinite_rhs;
static long underflows_at_call, nonfinite_at_call;
static int stopped_for_underflow;

/* callbacks::error_weights with the engine's error_scales for cvode-bdf: ewt_i =
 * 1/(tol_i + atol_i), tol = (rtol·|u|, max(0.1·rtol, 100 ulps of w), rtol·|θ|). */
static int ewt(N_Vector yv, N_Vector w, void *user_data) {
  const double *y = N_VGetArrayPointer(yv);
  double *e = N_VGetArrayPointer(w);
  const double tols[NEQ] = {RTOL * fabs(y[U]), fmax(RTOL * 0.1, 100.0 * DBL_EPSILON * fabs(y[W])),
                            RTOL * fabs(y[TH])};
  int i;
  (void)user_data;
  for (i = 0; i < NEQ; i++) {
    double tol = tols[i] + ATOL;
    if (!(tol > 0.0 && isfinite(tol))) return -1;
    e[i] = 1.0 / tol;
  }
  return 0;
}

static int rhs(realtype t, N_Vector yv, N_Vector ydot, void *user_data) {
  const double *y = N_VGetArrayPointer(yv);
  double *d = N_VGetArrayPointer(ydot);
  (void)t; (void)user_data;
  if (step_underflows > underflows_at_call) stopped_for_underflow = 1;
  if (stopped_for_underflow) return -1;
  model_rhs(y, d);
  if (all_finite(d, NEQ)) return 0;
  nonfinite_rhs++;
  return 1;
}

/* Drr::jacobian (same cases as model_rhs); the trampoline zero-fills the matrix first. */
static int jac(realtype t, N_Vector yv, N_Vector fy, SUNMatrix J, void *user_data,
               N_Vector tmp1, N_Vector tmp2, N_Vector tmp3) {
  const double *y = N_VGetArrayPointer(yv);
  double *data = SUNDenseMatrix_Data(J);
  int varies;
  double w = y[W];
  double slope = 1.0; /* resistance slope v f'(v) */
  double g = y[U] + (y[TH] + w) / XI;
  double a = arrest_rate(w, &varies);
  double da = varies ? a : 0.0;
  double c = 1.0 + EPS;
  double x = y[TH] / (1.0 + EPS) + w, s = 1.0;
  double v = exp(w);
  double law_f = -v * x, law_d1 = -v;
  (void)t; (void)fy; (void)user_data; (void)tmp1; (void)tmp2; (void)tmp3;
  memset(data, 0, NEQ * NEQ * sizeof *data);
  SM_ELEMENT_D(J, U, W) = exp(w);
  SM_ELEMENT_D(J, W, U) = -a;
  SM_ELEMENT_D(J, W, W) = da * g - a * slope / XI;
  SM_ELEMENT_D(J, W, TH) = -a / XI;
  SM_ELEMENT_D(J, TH, W) = c * (law_f + law_d1 * s);
  SM_ELEMENT_D(J, TH, TH) = law_d1;
  return all_finite(data, NEQ * NEQ) ? 0 : 1;
}

/* The last message CVODE reported (for the failure reason of the "wp" mode). */
static char last_message[512];

static void err_handler(int error_code, const char *module, const char *function, char *msg,
                        void *data) {
  (void)error_code; (void)module; (void)data;
  if (msg && strstr(msg, "t + h = t")) step_underflows++;
  if (msg) snprintf(last_message, sizeof last_message, "%s: %s", function, msg);
}

/* ------------------------------------------------------------ time (integrate/clock.rs) */

/* Time: an unevaluated sum hi + lo of two doubles. */
typedef struct {
  double hi, lo;
} Time;

/* Knuth's two-sum: a + b = *s + *e exactly. */
static void two_sum(double a, double b, double *s, double *e) {
  double ss = a + b;
  double bb = ss - a;
  *s = ss;
  *e = (a - (ss - bb)) + (b - bb);
}

static Time time_new(double t) {
  Time r;
  r.hi = t;
  r.lo = 0.0;
  return r;
}

/* Time::plus */
static Time time_plus(Time x, double dt) {
  double s, e;
  Time r;
  two_sum(x.hi, dt, &s, &e);
  two_sum(s, e + x.lo, &r.hi, &r.lo);
  return r;
}

/* Time::since: x − earlier, rounded once. */
static double time_since(Time x, Time earlier) {
  double s, e;
  two_sum(x.hi, -earlier.hi, &s, &e);
  return s + (e + (x.lo - earlier.lo));
}

/* Clock::step's fixed one-step horizon (clock.rs HORIZON). */
#define HORIZON 1.0e6
/* clock::RESTART_THRESHOLD: a restarting integrator is re-based when its last step falls
 * below this times |local t|. */
#define RESTART_THRESHOLD (1e4 * DBL_EPSILON)

/* ------------------------------------------------------------------ engine (cycle.rs) */

typedef struct {
  double t, y[NEQ], d[NEQ];
} Sample;

typedef struct {
  double t, x, dx;
} Knot;

typedef struct {
  double period, t0, slip_half_width, v_max, ln_v_max, v_min, ln_v_min, u_at_v_max,
      theta_at_v_max, u_min, u_max, theta_min, theta_max, slip, slip_duration;
  int has_half_width;
  long steps;
} CycleValues;

typedef struct {
  Time up; /* global time of the cycle's upward crossing of v = 1 */
  double u_start;
  int has_peak;
  double t_peak, y_peak[NEQ];
  int has_half_rise, has_half_fall, has_down;
  double half_rise, half_fall, t_down, u_down;
  double w_min, w_max, u_lo, u_hi, th_lo, th_hi;
  long steps_at_start;
} OpenCycle;

enum { EV_UP, EV_DOWN, EV_MAXW, EV_MINW, EV_EXT_U, EV_EXT_TH, EV_HALFFALL };

typedef struct {
  double t;
  int kind;
} Event;

typedef struct {
  long nst, nfe, nsetups, netf, nsolvefails, nni, ncfn, nje, nfeLS;
} Counters;

/* What the last CVode call did (Solver::advance's outcome). */
enum { ADV_OK, ADV_UNDERFLOW, ADV_FAIL };

typedef struct {
  /* the wrapper's Solver (src/sundials/solver.rs) */
  void *mem;
  N_Vector y, scratch;
  double tcur;         /* Solver::t: time of the last CVode return */
  double initial_step; /* the configured initial step (0: CVODE's estimate) */
  int rebased;         /* a re-base set its own initial step (restored at the next reinit) */
  long reinits;
  Counters before;     /* counters of the segments before the last CVodeReInit */
  /* the Clock (src/integrate/clock.rs) */
  Time epoch;          /* global time of local t = 0 */
  double last_step;
  long rebases, auto_rebases, underflow_retries;
  /* the Tracker (src/analysis/cycle.rs) */
  Sample prev;
  int has_open;
  OpenCycle open;
  CycleValues closed[MAX_CYCLES];
  int nclosed;
  Knot *rise; /* step ends of w since its last minimum */
  size_t nrise, cap_rise;
  Knot *knots; /* scratch for the half-rise crossing */
  size_t cap_knots;
  int rebase_in_rise; /* the clock is too coarse for the coming slip: re-base off the manifold */
  double rise_rate;   /* largest |dw/dt| since the last minimum of w */
  long steps;
  double fixed[NEQ];  /* the fixed point */
  int escaping;       /* steps limited to ESCAPE_NEAR (Tracker::escape) */
  long escapes;
  const char *failure;
} Tracker;

static void fail(Tracker *tr, const char *what) {
  if (!tr->failure) tr->failure = what;
}

static void read_counters(void *mem, Counters *c) {
  CVodeGetNumSteps(mem, &c->nst);
  CVodeGetNumRhsEvals(mem, &c->nfe);
  CVodeGetNumLinSolvSetups(mem, &c->nsetups);
  CVodeGetNumErrTestFails(mem, &c->netf);
  CVodeGetNumStepSolveFails(mem, &c->nsolvefails);
  CVodeGetNumNonlinSolvIters(mem, &c->nni);
  CVodeGetNumNonlinSolvConvFails(mem, &c->ncfn);
  CVodeGetNumJacEvals(mem, &c->nje);
  CVodeGetNumLinRhsEvals(mem, &c->nfeLS);
}

static void add_counters(Counters *sum, const Counters *c) {
  sum->nst += c->nst; sum->nfe += c->nfe; sum->nsetups += c->nsetups; sum->netf += c->netf;
  sum->nsolvefails += c->nsolvefails; sum->nni += c->nni; sum->ncfn += c->ncfn;
  sum->nje += c->nje; sum->nfeLS += c->nfeLS;
}

/* ---- Solver (src/sundials/solver.rs) */

/* Solver::advance with CV_ONE_STEP: the outcome as the wrapper classifies it (a "t + h = t"
 * during the call is a StepUnderflow error unless a right-hand side was non-finite). */
static int solver_advance(Tracker *tr, double tout, double *tret) {
  double t = tr->tcur;
  long nonfinite, underflows;
  int flag;
  last_message[0] = '\0';
  stopped_for_underflow = 0;
  underflows_at_call = step_underflows;
  nonfinite_at_call = nonfinite_rhs;
  flag = CVode(tr->mem, tout, tr->y, &t, CV_ONE_STEP);
  tr->tcur = t;
  *tret = t;
  nonfinite = nonfinite_rhs - nonfinite_at_call;
  underflows = step_underflows - underflows_at_call;
  if (stopped_for_underflow) return nonfinite > 0 ? ADV_FAIL : ADV_UNDERFLOW;
  if (flag < 0) return nonfinite == 0 && underflows > 0 ? ADV_UNDERFLOW : ADV_FAIL;
  if (underflows > 0) return ADV_UNDERFLOW;
  return ADV_OK;
}

/* Solver::reinit: CVodeReInit at (t0, y0) keeping the counters in `before`; a re-base's own
 * initial step is replaced by the configured one. */
static int solver_reinit(Tracker *tr, double t0, const double *y0) {
  Counters c;
  read_counters(tr->mem, &c);
  memcpy(N_VGetArrayPointer(tr->y), y0, NEQ * sizeof *y0);
  if (CVodeReInit(tr->mem, t0, tr->y) < 0) {
    fail(tr, "CVodeReInit");
    return -1;
  }
  add_counters(&tr->before, &c);
  tr->tcur = t0;
  tr->reinits++;
  if (tr->rebased) {
    tr->rebased = 0;
    if (CVodeSetInitStep(tr->mem, tr->initial_step) != CV_SUCCESS) {
      fail(tr, "CVodeSetInitStep");
      return -1;
    }
  }
  return 0;
}

/* Solver::restart: reinit at (t0, y0), with first_step as the first step when it is finite
 * and positive (pass 0 for none). */
static int solver_restart(Tracker *tr, double t0, const double *y0, double first_step) {
  if (solver_reinit(tr, t0, y0)) return -1;
  if (isfinite(first_step) && first_step > 0.0) {
    if (CVodeSetInitStep(tr->mem, first_step) != CV_SUCCESS) {
      fail(tr, "CVodeSetInitStep");
      return -1;
    }
    tr->rebased = 1;
  }
  return 0;
}

/* Solver::rebase: restart at (0, state). */
static int solver_rebase(Tracker *tr, double first_step) {
  double y[NEQ];
  memcpy(y, N_VGetArrayPointer(tr->y), sizeof y);
  return solver_restart(tr, 0.0, y, first_step);
}

/* Solver::set_max_step (0: no limit); restarts at the last returned point, with the limit as
 * the first step, when the current step is above it. */
static int solver_set_max_step(Tracker *tr, double max_step) {
  double current, y[NEQ];
  if (CVodeSetMaxStep(tr->mem, max_step) != CV_SUCCESS) {
    fail(tr, "CVodeSetMaxStep");
    return -1;
  }
  if (max_step > 0.0) {
    CVodeGetCurrentStep(tr->mem, &current);
    if (fabs(current) > max_step) {
      memcpy(y, N_VGetArrayPointer(tr->y), sizeof y);
      return solver_restart(tr, tr->tcur, y, max_step);
    }
  }
  return 0;
}

/* ---- Clock (src/integrate/clock.rs) */

static Time clock_global(const Tracker *tr, double t) { return time_plus(tr->epoch, t); }

/* Clock::rebase_with: moves the local origin to the current point; *shift = the local time it
 * had. first_step: 0 for none. */
static int clock_rebase_with(Tracker *tr, double first_step, double *shift) {
  double t = tr->tcur;
  if (t != 0.0) {
    if (solver_rebase(tr, first_step)) return -1;
    tr->epoch = time_plus(tr->epoch, t);
    tr->rebases++;
  }
  *shift = t;
  return 0;
}

/* Clock::step: one internal step, re-basing first if the last step fell below the threshold;
 * on a step underflow inside the call, re-base with the current step and try once more.
 * *start: local time where the step started, *t: where it ended. */
static int clock_step(Tracker *tr, double *start, double *t) {
  double shift;
  int r;
  if (tr->last_step < RESTART_THRESHOLD * fabs(tr->tcur)) {
    if (clock_rebase_with(tr, tr->last_step, &shift)) return -1;
    tr->auto_rebases++;
  }
  *start = tr->tcur;
  r = solver_advance(tr, *start + HORIZON, t);
  if (r == ADV_UNDERFLOW && *start != 0.0) {
    double h;
    CVodeGetCurrentStep(tr->mem, &h);
    h = fabs(h);
    if (clock_rebase_with(tr, h > 0.0 ? h : 0.0, &shift)) return -1;
    tr->underflow_retries++;
    *start = 0.0;
    r = solver_advance(tr, HORIZON, t);
  }
  if (r != ADV_OK) {
    fail(tr, r == ADV_UNDERFLOW ? "t + h = t" : "CVode");
    return -1;
  }
  tr->last_step = fabs(*t - *start);
  return 0;
}

/* ---- Tracker */

/* Component `index` of the k-th derivative of the interpolant at t. */
static int dense(Tracker *tr, double t, int k, const double **out) {
  if (CVodeGetDky(tr->mem, t, k, tr->scratch) < 0) {
    fail(tr, "CVodeGetDky");
    return -1;
  }
  *out = N_VGetArrayPointer(tr->scratch);
  return 0;
}

static double signum(double x) { return isnan(x) ? NAN : copysign(1.0, x); }

/* events::refine: Illinois (modified regula falsi) on the dense output. */
static int refine(Tracker *tr, double a, double b, int k, int index, double level, double *root) {
  const double *d;
  double ta = a, tb = b, fa, fb;
  int side = 0, it;
  if (dense(tr, ta, k, &d)) return -1;
  fa = d[index] - level;
  if (dense(tr, tb, k, &d)) return -1;
  fb = d[index] - level;
  if (fa == 0.0) {
    *root = ta;
    return 0;
  }
  if (fb == 0.0 || signum(fa) == signum(fb)) {
    *root = tb;
    return 0;
  }
  for (it = 0; it < 200; it++) {
    double width = tb - ta, t, f;
    if (fabs(width) <= 4.0 * DBL_EPSILON * fmax(fabs(ta), fabs(tb)) + DBL_MIN) break;
    t = tb - fb * width / (fb - fa);
    if (!(t > fmin(ta, tb) && t < fmax(ta, tb))) t = 0.5 * (ta + tb);
    if (dense(tr, t, k, &d)) return -1;
    f = d[index] - level;
    if (f == 0.0) {
      *root = t;
      return 0;
    }
    if (signum(f) == signum(fb)) {
      tb = t;
      fb = f;
      if (side == 1) fa *= 0.5;
      side = 1;
    } else {
      ta = t;
      fa = f;
      if (side == -1) fb *= 0.5;
      side = -1;
    }
  }
  *root = fabs(fa) < fabs(fb) ? ta : tb;
  return 0;
}

static double hermite(Knot a, Knot b, double t) {
  double h = b.t - a.t;
  double s = (t - a.t) / h;
  double s2 = s * s, s3 = s * s * s;
  return (2.0 * s3 - 3.0 * s2 + 1.0) * a.x + (s3 - 2.0 * s2 + s) * h * a.dx +
         (-2.0 * s3 + 3.0 * s2) * b.x + (s3 - s2) * h * b.dx;
}

/* events::last_upward_crossing */
static int last_upward_crossing(const Knot *knots, size_t n, double level, double *out) {
  size_t i, found = 0;
  int any = 0;
  Knot a, b;
  double lo, hi;
  int it;
  for (i = 0; i + 1 < n; i++)
    if (knots[i].x < level && knots[i + 1].x >= level) {
      found = i;
      any = 1;
    }
  if (!any) return 0;
  a = knots[found];
  b = knots[found + 1];
  lo = a.t;
  hi = b.t;
  for (it = 0; it < 200; it++) {
    double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    if (hermite(a, b, mid) < level)
      lo = mid;
    else
      hi = mid;
  }
  *out = 0.5 * (lo + hi);
  return 1;
}

/* Makes room for `need` knots in *buf. */
static void grow(Knot **buf, size_t *cap, size_t need) {
  size_t c = *cap ? *cap : 1024;
  Knot *p;
  if (need <= *cap) return;
  while (c < need) c *= 2;
  p = realloc(*buf, c * sizeof *p);
  if (!p) {
    fprintf(stderr, "earthquake_cvode: out of memory\n");
    exit(1);
  }
  *buf = p;
  *cap = c;
}

static void rise_push(Tracker *tr, Knot k) {
  grow(&tr->rise, &tr->cap_rise, tr->nrise + 1);
  tr->rise[tr->nrise++] = k;
}

/* f64::total_cmp for the (finite) event times, then a stable insertion sort. */
static int64_t total_key(double x) {
  int64_t bits;
  memcpy(&bits, &x, sizeof bits);
  return bits ^ (int64_t)(((uint64_t)(bits >> 63)) >> 1);
}

static int events(Tracker *tr, const Sample *next, Event *found) {
  const Sample *p = &tr->prev;
  double a = p->t, b = next->t, t;
  int n = 0, i, j, idx[2] = {U, TH};
  if (p->y[W] < 0.0 && next->y[W] >= 0.0) {
    if (refine(tr, a, b, 0, W, 0.0, &t)) return -1;
    found[n].t = t; found[n++].kind = EV_UP;
  }
  if (p->y[W] >= 0.0 && next->y[W] < 0.0) {
    if (refine(tr, a, b, 0, W, 0.0, &t)) return -1;
    found[n].t = t; found[n++].kind = EV_DOWN;
  }
  if (p->d[W] > 0.0 && next->d[W] <= 0.0) {
    if (refine(tr, a, b, 1, W, 0.0, &t)) return -1;
    found[n].t = t; found[n++].kind = EV_MAXW;
  }
  if (p->d[W] < 0.0 && next->d[W] >= 0.0) {
    if (refine(tr, a, b, 1, W, 0.0, &t)) return -1;
    found[n].t = t; found[n++].kind = EV_MINW;
  }
  for (i = 0; i < 2; i++) {
    int c = idx[i];
    if ((p->d[c] > 0.0) != (next->d[c] > 0.0)) {
      if (refine(tr, a, b, 1, c, 0.0, &t)) return -1;
      found[n].t = t; found[n++].kind = c == U ? EV_EXT_U : EV_EXT_TH;
    }
  }
  if (tr->has_open && tr->open.has_peak && !tr->open.has_half_fall) {
    double level = tr->open.w_max - LN_2;
    if (p->y[W] >= level && next->y[W] < level) {
      if (refine(tr, a, b, 0, W, level, &t)) return -1;
      found[n].t = t; found[n++].kind = EV_HALFFALL;
    }
  }
  for (i = 1; i < n; i++) {
    Event e = found[i];
    for (j = i; j > 0 && total_key(found[j - 1].t) > total_key(e.t); j--) found[j] = found[j - 1];
    found[j] = e;
  }
  return n;
}

static void update_ranges(Tracker *tr, const double *y) {
  OpenCycle *c = &tr->open;
  if (!tr->has_open) return;
  c->w_min = fmin(c->w_min, y[W]);
  c->w_max = fmax(c->w_max, y[W]);
  c->u_lo = fmin(c->u_lo, y[U]);
  c->u_hi = fmax(c->u_hi, y[U]);
  c->th_lo = fmin(c->th_lo, y[TH]);
  c->th_hi = fmax(c->th_hi, y[TH]);
}

static void close_cycle(Tracker *tr, const OpenCycle *c, double period) {
  CycleValues *v;
  double t_down, u_down;
  if (!c->has_peak) return; /* a sub-threshold wiggle */
  if (tr->nclosed >= MAX_CYCLES) {
    fail(tr, "too many cycles");
    return;
  }
  t_down = c->has_down ? c->t_down : period;
  u_down = c->has_down ? c->u_down : c->u_hi;
  v = &tr->closed[tr->nclosed++];
  v->period = period;
  v->t0 = c->t_peak;
  v->has_half_width = c->has_half_rise && c->has_half_fall;
  v->slip_half_width = v->has_half_width ? c->half_fall - c->half_rise : NAN;
  v->v_max = exp(c->w_max);
  v->ln_v_max = c->w_max;
  v->v_min = exp(c->w_min);
  v->ln_v_min = c->w_min;
  v->u_at_v_max = c->y_peak[U];
  v->theta_at_v_max = c->y_peak[TH];
  v->u_min = c->u_lo;
  v->u_max = c->u_hi;
  v->theta_min = c->th_lo;
  v->theta_max = c->th_hi;
  v->slip = (u_down - c->u_start) + t_down;
  v->slip_duration = t_down;
  v->steps = tr->steps - c->steps_at_start;
}

/* Tracker::handle: returns 1 when time must be re-based after this step (after the peak),
 * 0 otherwise, -1 on failure. */
static int handle(Tracker *tr, double t, int kind) {
  const double *d;
  double y[NEQ];
  if (dense(tr, t, 0, &d)) return -1;
  memcpy(y, d, sizeof y);
  update_ranges(tr, y);
  switch (kind) {
  case EV_UP: {
    OpenCycle *c = &tr->open;
    if (tr->has_open) {
      OpenCycle old = *c;
      close_cycle(tr, &old, time_since(clock_global(tr, t), old.up));
    }
    memset(c, 0, sizeof *c);
    c->up = clock_global(tr, t);
    c->u_start = y[U];
    c->w_min = c->w_max = y[W];
    c->u_lo = c->u_hi = y[U];
    c->th_lo = c->th_hi = y[TH];
    c->steps_at_start = tr->steps;
    tr->has_open = 1;
    tr->rebase_in_rise = GAMMA * t > 1.0 / (1e3 * DBL_EPSILON);
    break;
  }
  case EV_DOWN:
    if (tr->has_open && !tr->open.has_down) {
      tr->open.has_down = 1;
      tr->open.t_down = time_since(clock_global(tr, t), tr->open.up);
      tr->open.u_down = y[U];
    }
    break;
  case EV_MINW: {
    /* A wiggle during a rise (cycle open, no peak yet) keeps the rise buffer. */
    int rising = tr->has_open && !tr->open.has_peak;
    if (!rising) {
      Knot k = {t, y[W], 0.0};
      tr->rise_rate = 0.0;
      tr->nrise = 0;
      rise_push(tr, k);
    }
    break;
  }
  case EV_MAXW: {
    /* The cycle's peak is its highest maximum of w with v > 1. */
    OpenCycle *c = &tr->open;
    double level, tr_half;
    size_t i, n = 0;
    if (!tr->has_open) return 0;
    if (y[W] <= 0.0 || (c->has_peak && y[W] <= c->y_peak[W])) return 0;
    c->has_peak = 1;
    c->t_peak = time_since(clock_global(tr, t), c->up);
    memcpy(c->y_peak, y, sizeof y);
    level = y[W] - LN_2;
    /* knots = the rise buffer's knots before the event, then the peak knot */
    grow(&tr->knots, &tr->cap_knots, tr->nrise + 1);
    for (i = 0; i < tr->nrise; i++)
      if (tr->rise[i].t < t) tr->knots[n++] = tr->rise[i];
    tr->knots[n].t = t;
    tr->knots[n].x = y[W];
    tr->knots[n++].dx = 0.0;
    c->has_half_rise = last_upward_crossing(tr->knots, n, level, &tr_half);
    if (c->has_half_rise) c->half_rise = time_since(clock_global(tr, tr_half), c->up);
    c->has_half_fall = 0;
    tr->rebase_in_rise = 0;
    return 1;
  }
  case EV_HALFFALL:
    if (tr->has_open) {
      tr->open.has_half_fall = 1;
      tr->open.half_fall = time_since(clock_global(tr, t), tr->open.up);
    }
    break;
  default:
    break;
  }
  return 0;
}

/* Tracker::half_fall_in_peak_step: the half-maximum fall inside the step that holds the peak. */
static int half_fall_in_peak_step(Tracker *tr, const Sample *next) {
  OpenCycle *c = &tr->open;
  Time up;
  double level, t_local, t;
  if (!tr->has_open || !c->has_peak || c->has_half_fall) return 0;
  up = c->up;
  level = c->y_peak[W] - LN_2;
  t_local = c->t_peak - time_since(clock_global(tr, 0.0), up);
  if (next->y[W] < level && t_local < next->t) {
    if (refine(tr, t_local, next->t, 0, W, level, &t)) return -1;
    c->has_half_fall = 1;
    c->half_fall = time_since(clock_global(tr, t), up);
  }
  return 0;
}

/* cycle::restart_safe: the model's dw/dt at y (error: the solver's error in G, its w tolerance
 * times ∂G/∂w = 1/ξ, amplified by γ² e^{−w}) is resolved to 1e-3 of `rate`. */
static int restart_safe(const double *y, double rate) {
  double error_g = (RTOL * fabs(y[W]) + ATOL) * (1.0 / XI);
  return GAMMA * GAMMA * exp(-y[W]) * error_g <= 1e-3 * rate;
}

/* Tracker::shifted: the clock's origin moved `shift` later. */
static void shifted(Tracker *tr, double shift) {
  size_t i;
  for (i = 0; i < tr->nrise; i++) tr->rise[i].t -= shift;
  tr->prev.t -= shift;
}

/* Tracker::escape: limits the steps to ESCAPE_NEAR while the state rests within the
 * integration noise of the fixed point, back to MAX_STEP once ln v has left it by more than 1. */
static int escape(Tracker *tr) {
  const double *y = N_VGetArrayPointer(tr->y);
  int i, near = 1;
  if (tr->escaping) {
    if (fabs(y[W] - tr->fixed[W]) > 1.0) {
      tr->escaping = 0;
      return solver_set_max_step(tr, MAX_STEP);
    }
  } else {
    double floor_ = fmax(1e-9, 1e3 * (RTOL + ATOL)); /* noise_floor */
    for (i = 0; i < NEQ; i++) near &= fabs(y[i] - tr->fixed[i]) < floor_ * (1.0 + fabs(tr->fixed[i]));
    if (near) {
      tr->escaping = 1;
      tr->escapes++;
      return solver_set_max_step(tr, ESCAPE_NEAR);
    }
  }
  return 0;
}

/* Tracker::step */
static int step(Tracker *tr) {
  double start, t, shift;
  const double *d, *y;
  Sample next;
  Event found[8];
  int n, i, after_peak = 0, rebase, clock_exhausted;
  if (tr->prev.y[W] < ARREST_RATE_HELD_BELOW) {
    /* Drr::deep_stick may cross the stick in closed form here: not replicated */
    fail(tr, "a deep stick (ln v below the arrest-rate hold)");
    return -1;
  }
  if (clock_step(tr, &start, &t)) return -1;
  if (start != tr->prev.t) shifted(tr, tr->prev.t - start); /* the clock re-based */
  tr->steps++;
  y = N_VGetArrayPointer(tr->y);
  next.t = t;
  memcpy(next.y, y, sizeof next.y);
  if (dense(tr, t, 1, &d)) return -1;
  memcpy(next.d, d, sizeof next.d);
  if (!all_finite(next.y, NEQ) || !all_finite(next.d, NEQ)) {
    fail(tr, "the state or its derivative became non-finite");
    return -1;
  }
  tr->rise_rate = fmax(tr->rise_rate, fabs(next.d[W]));
  n = events(tr, &next, found);
  if (n < 0) return -1;
  for (i = 0; i < n; i++) {
    int r = handle(tr, found[i].t, found[i].kind);
    if (r < 0) return -1;
    after_peak |= r;
  }
  if (after_peak && half_fall_in_peak_step(tr, &next)) return -1;
  rebase = 0; /* no re-base after the peak for a restarting integrator (cycle.rs) */
  clock_exhausted = next.t - tr->prev.t < 1e4 * DBL_EPSILON * next.t;
  if (tr->rebase_in_rise && (restart_safe(next.y, fabs(next.d[W])) || clock_exhausted)) {
    tr->rebase_in_rise = 0;
    rebase = 1;
  }
  update_ranges(tr, next.y);
  if (tr->nrise > 0 && next.t > tr->rise[tr->nrise - 1].t) {
    Knot k = {next.t, next.y[W], next.d[W]};
    rise_push(tr, k);
  }
  tr->prev = next;
  if (rebase) {
    /* Tracker::restart: Clock::rebase at the step end */
    if (clock_rebase_with(tr, 0.0, &shift)) return -1;
    shifted(tr, shift);
  }
  return 0;
}

typedef struct {
  CycleValues cycles[MAX_CYCLES];
  int ncycles;
  long steps, reinits, rebases, auto_rebases, underflow_retries, escapes, step_underflows;
  double time_integrated;
  Counters counters;
} Result;

static volatile double v0_in = V0; /* keeps log(0.45) a runtime glibc call, as in Rust */

/* Why the last run failed, and whether to keep quiet about it (the "wp" mode reports it). */
static char failure_reason[1024];
static int quiet_failures = 0;

/* One run: create, integrate through n_cycles closed cycles, read counters, free. */
static int run_once(int n_cycles, Result *out) {
  SUNContext ctx = NULL;
  N_Vector atol = NULL;
  SUNMatrix A = NULL;
  SUNLinearSolver LS = NULL;
  Tracker tr;
  Counters last;
  Time t_start;
  int status = 1, i, seen = 0;
  double y0[NEQ];

  memset(&tr, 0, sizeof tr);
  last_message[0] = '\0';
  step_underflows = nonfinite_rhs = 0;
  if (SUNContext_Create(NULL, &ctx) != 0) return 1;
  tr.y = N_VNew_Serial(NEQ, ctx);
  tr.scratch = N_VNew_Serial(NEQ, ctx);
  atol = N_VNew_Serial(NEQ, ctx);
  if (!tr.y || !tr.scratch || !atol) goto done;
  y0[U] = U0;
  y0[W] = w0_given ? W0 : log(v0_in);
  y0[TH] = THETA0;
  memcpy(N_VGetArrayPointer(tr.y), y0, sizeof y0);
  N_VScale(1.0, tr.y, tr.scratch);
  for (i = 0; i < NEQ; i++) NV_Ith_S(atol, i) = ATOL;
  /* Drr::fixed_point: (−(θ* + f(1) + η)/ξ, 0, θ* = (1+ε)(x* − f(1))), f(1) = 0, x* = 0 */
  tr.fixed[TH] = (1.0 + EPS) * (0.0 - 0.0);
  tr.fixed[U] = -(tr.fixed[TH] + 0.0 + 0.0) / XI;
  tr.fixed[W] = 0.0;

  /* engine::integrator_for: a start far from v = 1 (|ln v| > 30) begins with a step that
   * changes each component by at most 1e-3 of max(1, |y|) */
  tr.initial_step = 0.0;
  if (fabs(y0[W]) > 30.0) {
    double f[NEQ], h = INFINITY;
    model_rhs(y0, f);
    for (i = 0; i < NEQ; i++) h = fmin(h, 1e-3 * fmax(fabs(y0[i]), 1.0) / fmax(fabs(f[i]), 1e-300));
    if (isfinite(h) && h > 0.0) tr.initial_step = h;
  }

  tr.mem = CVodeCreate(CV_BDF, ctx);
  if (!tr.mem) goto done;
  if (CVodeInit(tr.mem, rhs, 0.0, tr.y) != CV_SUCCESS) goto done;
  if (CVodeSetErrHandlerFn(tr.mem, err_handler, NULL) != CV_SUCCESS) goto done;
  if (CVodeSetMaxHnilWarns(tr.mem, INT_MAX) != CV_SUCCESS) goto done;
  if (CVodeSVtolerances(tr.mem, RTOL, atol) != CV_SUCCESS) goto done;
  if (CVodeWFtolerances(tr.mem, ewt) != CV_SUCCESS) goto done;
  /* Solver::apply_options with the engine's Options: max_steps = DEFAULT_MAX_STEPS, the
   * initial step above if any, max_step = 1/8 of the linear period (MAX_STEP), at most 20
   * error-test failures per step. */
  if (CVodeSetMaxNumSteps(tr.mem, 1000000L) != CV_SUCCESS) goto done;
  if (tr.initial_step > 0.0 && CVodeSetInitStep(tr.mem, tr.initial_step) != CV_SUCCESS) goto done;
  if (MAX_STEP > 0.0 && CVodeSetMaxStep(tr.mem, MAX_STEP) != CV_SUCCESS) goto done;
  if (CVodeSetMaxErrTestFails(tr.mem, 20) != CV_SUCCESS) goto done;
  if (CVodeSetMaxConvFails(tr.mem, 20) != CV_SUCCESS) goto done;
  A = SUNDenseMatrix(NEQ, NEQ, ctx);
  if (!A) goto done;
  LS = SUNLinSol_Dense(tr.y, A, ctx);
  if (!LS) goto done;
  if (CVodeSetLinearSolver(tr.mem, LS, A) != CVLS_SUCCESS) goto done;
  if (CVodeSetJacFn(tr.mem, jac) != CVLS_SUCCESS) goto done;
  /* engine::integrator: jacobian_max_age = 1 (a linear-solver setup and a Jacobian at every
   * step; docs/robustness.md) */
  if (CVodeSetLSetupFrequency(tr.mem, 1) != CV_SUCCESS) goto done;
  if (CVodeSetJacEvalFrequency(tr.mem, 1) != CVLS_SUCCESS) goto done;

  /* cycle::analyse: first_sample (the RHS gives the derivative at the start), the Clock from
   * global time 0 */
  tr.prev.t = 0.0;
  memcpy(tr.prev.y, y0, sizeof tr.prev.y);
  model_rhs(tr.prev.y, tr.prev.d);
  t_start = time_new(tr.tcur);
  tr.epoch = time_plus(t_start, -tr.tcur);
  tr.last_step = INFINITY;

  /* cycle::analyse's loop, stopping after n_cycles closed cycles */
  while (1) {
    double time;
    int out_of_time;
    if (step(&tr)) goto done;
    if (ESCAPE_NEAR > 0.0 && escape(&tr)) goto done;
    if (tr.steps > MAX_STEPS) {
      fail(&tr, "cycle.max_steps");
      goto done;
    }
    time = time_since(clock_global(&tr, tr.tcur), t_start);
    if (tr.nclosed > seen) {
      seen = tr.nclosed;
      /* decaying() is false at an unstable fixed point; periodicity() is replaced by: */
      if (tr.nclosed >= n_cycles) break;
    }
    out_of_time = time >= MAX_TIME;
    /* the fixed-point test runs only at a linearly stable fixed point: never here (the bench
     * asserts that the scene's is unstable) */
    if (out_of_time) {
      fail(&tr, "cycle.max_time");
      goto done;
    }
  }
  memcpy(out->cycles, tr.closed, (size_t)tr.nclosed * sizeof *tr.closed);
  out->ncycles = tr.nclosed;
  out->steps = tr.steps;
  out->reinits = tr.reinits;
  out->rebases = tr.rebases;
  out->auto_rebases = tr.auto_rebases;
  out->underflow_retries = tr.underflow_retries;
  out->escapes = tr.escapes;
  out->step_underflows = step_underflows;
  out->time_integrated = time_since(clock_global(&tr, tr.tcur), t_start);
  read_counters(tr.mem, &last);
  out->counters = tr.before;
  add_counters(&out->counters, &last);
  status = 0;

done:
  if (status) {
    snprintf(failure_reason, sizeof failure_reason, "%s%s%s at t = %.17g",
             tr.failure ? tr.failure : "setup failed", last_message[0] ? " — " : "", last_message,
             tr.mem ? time_since(clock_global(&tr, tr.tcur), time_new(0.0)) : 0.0);
    if (!quiet_failures) fprintf(stderr, "earthquake_cvode: %s\n", failure_reason);
  }
  if (tr.mem) CVodeFree(&tr.mem);
  if (LS) SUNLinSolFree(LS);
  if (A) SUNMatDestroy(A);
  if (atol) N_VDestroy(atol);
  if (tr.scratch) N_VDestroy(tr.scratch);
  if (tr.y) N_VDestroy(tr.y);
  free(tr.rise);
  free(tr.knots);
  SUNContext_Free(&ctx);
  return status;
}

static long long now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static Result result; /* latest run */

static void must_run(int n_cycles) {
  if (run_once(n_cycles, &result) != 0) {
    fprintf(stderr, "earthquake_cvode: run failed\n");
    exit(1);
  }
}

static int parse_cycles(const char *s) {
  long n = strtol(s, NULL, 10);
  if (n < 1 || n > MAX_CYCLES) {
    fprintf(stderr, "earthquake_cvode: N must be 1..%d\n", MAX_CYCLES);
    exit(64);
  }
  return (int)n;
}

/* A number argument of the "wp" mode; exits 64 if it is not one. */
static double number(const char *s) {
  char *end;
  double x = strtod(s, &end);
  if (end == s || *end != '\0' || !isfinite(x)) {
    fprintf(stderr, "earthquake_cvode: \"%s\" is not a finite number\n", s);
    exit(64);
  }
  return x;
}

/* Prints s as a JSON string (it holds no control characters). */
static void json_string(const char *s) {
  putchar('"');
  for (; *s; s++) {
    if (*s == '"' || *s == '\\') putchar('\\');
    putchar(*s);
  }
  putchar('"');
}

/* earthquake_cvode wp GAMMA RTOL ATOL MAX_STEP U0 W0 THETA0 N RUNS BUDGET_S: the work-precision
 * benchmark (benches/work_precision): one untimed warm-up run, then up to RUNS timed runs of N
 * cycles from (U0, W0, THETA0), stopping once the timed runs add up to BUDGET_S seconds (a
 * warm-up longer than that is the only, timed, run). Prints one JSON line: the means over the
 * N cycles of the period, t0 and ln v_max, the minimum time per cycle, the counters of one
 * run, or the failure with its reason. */
static int work_precision(char **argv) {
  long runs, done = 0, k;
  int n_cycles;
  double budget, spent = 0.0, best = INFINITY, period = 0.0, t0 = 0.0, ln_v_max = 0.0;
  long long start;
  const Counters *c = &result.counters;
  GAMMA = number(argv[2]);
  GAMMA2 = GAMMA * GAMMA;
  RTOL = number(argv[3]);
  ATOL = number(argv[4]);
  MAX_STEP = number(argv[5]);
  U0 = number(argv[6]);
  W0 = number(argv[7]);
  w0_given = 1;
  THETA0 = number(argv[8]);
  n_cycles = parse_cycles(argv[9]);
  runs = strtol(argv[10], NULL, 10);
  budget = number(argv[11]);
  if (runs < 1) return 64;
  quiet_failures = 1;
  printf("{\"method\":\"c-cvode-bdf\",\"gamma\":%.17g,\"rtol\":%.17g,\"atol\":%.17g,", GAMMA,
         RTOL, ATOL);
  start = now_ns();
  if (run_once(n_cycles, &result) != 0) {
    printf("\"ok\":false,\"error\":");
    json_string(failure_reason);
    printf("}\n");
    return 0;
  }
  spent = (double)(now_ns() - start) * 1e-9;
  if (spent > budget) {
    best = spent;
    done = 1;
  } else {
    spent = 0.0;
    while (done < runs && spent < budget) {
      double t;
      start = now_ns();
      if (run_once(n_cycles, &result) != 0) {
        printf("\"ok\":false,\"error\":");
        json_string(failure_reason);
        printf("}\n");
        return 0;
      }
      t = (double)(now_ns() - start) * 1e-9;
      spent += t;
      best = fmin(best, t);
      done++;
    }
  }
  for (k = 0; k < result.ncycles; k++) {
    period += result.cycles[k].period;
    t0 += result.cycles[k].t0;
    ln_v_max += result.cycles[k].ln_v_max;
  }
  printf("\"ok\":true,\"cycles\":%d,\"period\":%.17g,\"t0\":%.17g,\"ln_v_max\":%.17g,"
         "\"time_per_cycle_s\":%.9g,\"runs\":%ld,\"steps\":%ld,\"rhs\":%ld,\"jac\":%ld,"
         "\"lu\":%ld,\"rejected\":%ld}\n",
         result.ncycles, period / result.ncycles, t0 / result.ncycles, ln_v_max / result.ncycles,
         best / n_cycles, done, c->nst, c->nfe + c->nfeLS, c->nje, c->nsetups,
         c->netf + c->nsolvefails);
  return 0;
}

/* The optional "MAX_STEP ESCAPE_NEAR" after N in the modes other than "wp": the engine's max
 * step (1/8 of the linear period) and EscapeStep::near (0: none); *argc drops them. */
static void limits(int *argc, char **argv, int first) {
  if (*argc == first + 2) {
    MAX_STEP = number(argv[first]);
    ESCAPE_NEAR = number(argv[first + 1]);
    *argc -= 2;
  }
}

int main(int argc, char **argv) {
  long r, i;
  int n_cycles = 5;
  if (argc >= 2 && strcmp(argv[1], "wp") == 0) {
    if (argc != 12) {
      fprintf(stderr, "usage: %s wp GAMMA RTOL ATOL MAX_STEP U0 W0 THETA0 N RUNS BUDGET_S\n",
              argv[0]);
      return 64;
    }
    return work_precision(argv);
  }
  if (argc >= 2 && strcmp(argv[1], "check") == 0) {
    int k;
    const Counters *c = &result.counters;
    limits(&argc, argv, 3);
    if (argc == 3) n_cycles = parse_cycles(argv[2]);
    else if (argc > 3) return 64;
    must_run(n_cycles);
    for (k = 0; k < result.ncycles; k++) {
      const CycleValues *v = &result.cycles[k];
      printf("cycle %d steps %ld period %.17e t0 %.17e ln_v_max %.17e ln_v_min %.17e "
             "slip %.17e slip_half_width %.17e\n",
             k, v->steps, v->period, v->t0, v->ln_v_max, v->ln_v_min, v->slip,
             v->slip_half_width);
    }
    printf("time_integrated %.17e\nreinits %ld\n", result.time_integrated, result.reinits);
    printf("max_step %.17e\nescape_near %.17e\n", MAX_STEP, ESCAPE_NEAR);
    printf("clock_rebases %ld\nclock_rebases_automatic %ld\nunderflow_retries %ld\n"
           "fixed_point_escapes %ld\nstep_underflows %ld\n",
           result.rebases, result.auto_rebases, result.underflow_retries, result.escapes,
           result.step_underflows);
    printf("steps %ld\nrhs_evals %ld\nlin_setups %ld\nerr_test_fails %ld\n"
           "step_solve_fails %ld\nnonlin_iters %ld\nnonlin_conv_fails %ld\njac_evals %ld\n"
           "rhs_evals_jacobian %ld\n",
           c->nst, c->nfe, c->nsetups, c->netf, c->nsolvefails, c->nni, c->ncfn, c->nje,
           c->nfeLS);
    if (c->nst != result.steps) {
      fprintf(stderr, "earthquake_cvode: CVODE counted %ld steps, the loop %ld\n", c->nst,
              result.steps);
      return 1;
    }
    return 0;
  }
  if (argc < 2 || (r = strtol(argv[1], NULL, 10)) < 1) {
    fprintf(stderr,
            "usage: %s R [N [MAX_STEP ESCAPE_NEAR]] | %s R each [N [MAX_STEP ESCAPE_NEAR]] | "
            "%s check [N [MAX_STEP ESCAPE_NEAR]] | %s wp ...\n",
            argv[0], argv[0], argv[0], argv[0]);
    return 64;
  }
  if (argc >= 3 && strcmp(argv[2], "each") == 0) {
    long long *times;
    limits(&argc, argv, 4);
    if (argc == 4) n_cycles = parse_cycles(argv[3]);
    else if (argc > 4) return 64;
    times = malloc((size_t)r * sizeof *times);
    if (!times) return 1;
    for (i = 0; i < EACH_WARMUP; i++) must_run(n_cycles);
    for (i = 0; i < r; i++) {
      long long start = now_ns();
      must_run(n_cycles);
      times[i] = now_ns() - start;
    }
    for (i = 0; i < r; i++) printf("%lld\n", times[i]);
    free(times);
    return 0;
  } else {
    long long start, stop;
    long total_steps = 0;
    limits(&argc, argv, 3);
    if (argc == 3) n_cycles = parse_cycles(argv[2]);
    else if (argc > 3) return 64;
    for (i = 0; i < WARMUP; i++) must_run(n_cycles);
    start = now_ns();
    for (i = 0; i < r; i++) {
      must_run(n_cycles);
      total_steps += result.steps;
    }
    stop = now_ns();
    printf("elapsed_ns %lld\nsteps %ld\nperiod %.17e\n", stop - start, total_steps,
           result.cycles[result.ncycles - 1].period);
  }
  return 0;
}
