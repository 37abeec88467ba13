/* Plain-C reference for the Robertson benchmark (benches/robertson.rs).
 *
 * Runs SUNDIALS' example cvode/serial/cvRoberts_dns.c with identical solver settings (CVODE
 * BDF, rtol 1e-4, atol (1e-8, 1e-14, 1e-6), dense matrix + dense linear solver, analytic
 * Jacobian, 2 root functions, outputs at 0.4*10^k for k = 0..11, a root return does not
 * advance tout) but without any I/O in the timed part. Each run creates the context, the
 * vectors, the solver, integrates, reads the counters and frees everything, exactly like
 * stickslip::model::robertson::cvode_example() does on the Rust side.
 *
 * Usage:
 *   robertson_cvode N        run the example N times (after WARMUP untimed runs) and print
 *                            the total elapsed nanoseconds of the N runs (CLOCK_MONOTONIC)
 *   robertson_cvode N each   time N runs individually (after EACH_WARMUP untimed runs) and
 *                            print each run's nanoseconds on its own line
 *   robertson_cvode check    run once and print every output row (%.17e) and the counters
 *
 * Every mode checks the last run against the example's reference solution at t = 4e10 (its
 * check_ans) and exits with status 2 if it does not match, so a broken build cannot pass.
 */
#define _POSIX_C_SOURCE 199309L

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#define NEQ 3
#define RTOL 1.0e-4
#define ATOL1 1.0e-8
#define ATOL2 1.0e-14
#define ATOL3 1.0e-6
#define T0 0.0
#define T1 0.4
#define TMULT 10.0
#define NOUT 12
#define MAX_ROWS 64
#define WARMUP 3
#define EACH_WARMUP 50

typedef struct {
  double t, y[NEQ];
  int is_root, roots[2];
} Row;

typedef struct {
  Row rows[MAX_ROWS];
  int nrows;
  long nst, nfe, nsetups, netf, nsolvefails, nni, ncfn, nje, nfeLS, nge, nslred;
  double hlast, hcur, hinused;
  int qlast;
} Run;

static int f(realtype t, N_Vector y, N_Vector ydot, void *user_data) {
  realtype *yv = N_VGetArrayPointer(y), *dv = N_VGetArrayPointer(ydot);
  realtype yd1 = dv[0] = -0.04 * yv[0] + 1.0e4 * yv[1] * yv[2];
  realtype yd3 = dv[2] = 3.0e7 * yv[1] * yv[1];
  dv[1] = -yd1 - yd3;
  (void)t; (void)user_data;
  return 0;
}

static int g(realtype t, N_Vector y, realtype *gout, void *user_data) {
  realtype *yv = N_VGetArrayPointer(y);
  gout[0] = yv[0] - 0.0001;
  gout[1] = yv[2] - 0.01;
  (void)t; (void)user_data;
  return 0;
}

static int Jac(realtype t, N_Vector y, N_Vector fy, SUNMatrix J, void *user_data,
               N_Vector tmp1, N_Vector tmp2, N_Vector tmp3) {
  realtype *yv = N_VGetArrayPointer(y);
  realtype y2 = yv[1], y3 = yv[2];
  SM_ELEMENT_D(J, 0, 0) = -0.04;
  SM_ELEMENT_D(J, 0, 1) = 1.0e4 * y3;
  SM_ELEMENT_D(J, 0, 2) = 1.0e4 * y2;
  SM_ELEMENT_D(J, 1, 0) = 0.04;
  SM_ELEMENT_D(J, 1, 1) = -1.0e4 * y3 - 6.0e7 * y2;
  SM_ELEMENT_D(J, 1, 2) = -1.0e4 * y2;
  SM_ELEMENT_D(J, 2, 0) = 0.0;
  SM_ELEMENT_D(J, 2, 1) = 6.0e7 * y2;
  SM_ELEMENT_D(J, 2, 2) = 0.0;
  (void)t; (void)fy; (void)user_data; (void)tmp1; (void)tmp2; (void)tmp3;
  return 0;
}

/* One full example: create, integrate, read counters, free. Returns 0 on success. */
static int run_example(Run *out) {
  SUNContext ctx = NULL;
  N_Vector y = NULL, abstol = NULL;
  SUNMatrix A = NULL;
  SUNLinearSolver LS = NULL;
  void *mem = NULL;
  int status = 1;
  realtype t, tout;
  int iout;

  out->nrows = 0;
  if (SUNContext_Create(NULL, &ctx) != 0) return 1;
  y = N_VNew_Serial(NEQ, ctx);
  abstol = N_VNew_Serial(NEQ, ctx);
  if (!y || !abstol) goto done;
  NV_Ith_S(y, 0) = 1.0; NV_Ith_S(y, 1) = 0.0; NV_Ith_S(y, 2) = 0.0;
  NV_Ith_S(abstol, 0) = ATOL1; NV_Ith_S(abstol, 1) = ATOL2; NV_Ith_S(abstol, 2) = ATOL3;

  mem = CVodeCreate(CV_BDF, ctx);
  if (!mem) goto done;
  if (CVodeInit(mem, f, T0, y) != CV_SUCCESS) goto done;
  if (CVodeSVtolerances(mem, RTOL, abstol) != CV_SUCCESS) goto done;
  if (CVodeRootInit(mem, 2, g) != CV_SUCCESS) goto done;
  A = SUNDenseMatrix(NEQ, NEQ, ctx);
  if (!A) goto done;
  LS = SUNLinSol_Dense(y, A, ctx);
  if (!LS) goto done;
  if (CVodeSetLinearSolver(mem, LS, A) != CVLS_SUCCESS) goto done;
  if (CVodeSetJacFn(mem, Jac) != CVLS_SUCCESS) goto done;

  iout = 0; tout = T1;
  while (1) {
    int retval = CVode(mem, tout, y, &t, CV_NORMAL);
    Row *r;
    if (retval < 0) goto done;
    if (out->nrows >= MAX_ROWS) goto done;
    r = &out->rows[out->nrows++];
    r->t = t;
    memcpy(r->y, N_VGetArrayPointer(y), sizeof r->y);
    r->is_root = (retval == CV_ROOT_RETURN);
    r->roots[0] = r->roots[1] = 0;
    if (r->is_root && CVodeGetRootInfo(mem, r->roots) != CV_SUCCESS) goto done;
    if (retval == CV_SUCCESS) {
      iout++;
      tout *= TMULT;
    }
    if (iout == NOUT) break;
  }

  /* The same counters stickslip's Solver::stats() reads. */
  CVodeGetNumSteps(mem, &out->nst);
  CVodeGetNumRhsEvals(mem, &out->nfe);
  CVodeGetNumLinSolvSetups(mem, &out->nsetups);
  CVodeGetNumErrTestFails(mem, &out->netf);
  CVodeGetNumStepSolveFails(mem, &out->nsolvefails);
  CVodeGetNumNonlinSolvIters(mem, &out->nni);
  CVodeGetNumNonlinSolvConvFails(mem, &out->ncfn);
  CVodeGetNumJacEvals(mem, &out->nje);
  CVodeGetNumLinRhsEvals(mem, &out->nfeLS);
  CVodeGetNumGEvals(mem, &out->nge);
  CVodeGetNumStabLimOrderReds(mem, &out->nslred);
  CVodeGetLastStep(mem, &out->hlast);
  CVodeGetCurrentStep(mem, &out->hcur);
  CVodeGetActualInitStep(mem, &out->hinused);
  CVodeGetLastOrder(mem, &out->qlast);
  status = 0;

done:
  if (mem) CVodeFree(&mem);
  if (LS) SUNLinSolFree(LS);
  if (A) SUNMatDestroy(A);
  if (abstol) N_VDestroy(abstol);
  if (y) N_VDestroy(y);
  SUNContext_Free(&ctx);
  return status;
}

/* The example's check_ans: WRMS error against its reference at t = 4e10, with atol loosened
 * tenfold, must be < 1. Returns 0 on pass. */
static int check_ans(const Run *run) {
  static const double ref[NEQ] = {5.2083495894337328e-08, 2.0833399429795671e-13,
                                  9.9999994791629776e-01};
  static const double atol[NEQ] = {ATOL1, ATOL2, ATOL3};
  const Row *last;
  double sum = 0.0, err;
  int i;
  if (run->nrows < 1) return 1;
  last = &run->rows[run->nrows - 1];
  if (last->t != 4.0e10) {
    fprintf(stderr, "robertson_cvode: last output at t = %.17e, expected 4e10\n", last->t);
    return 1;
  }
  for (i = 0; i < NEQ; i++) {
    double w = 1.0 / (RTOL * fabs(ref[i]) + 10.0 * atol[i]);
    double d = (last->y[i] - ref[i]) * w;
    sum += d * d;
  }
  err = sqrt(sum / NEQ);
  if (!(err < 1.0)) {
    fprintf(stderr, "robertson_cvode: check_ans failed, WRMS error = %g\n", err);
    return 1;
  }
  return 0;
}

static long long now_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static Run run; /* result of the latest run (static: no allocation in the timed loop) */

static void must_run(void) {
  if (run_example(&run) != 0) {
    fprintf(stderr, "robertson_cvode: a SUNDIALS call failed\n");
    exit(1);
  }
}

int main(int argc, char **argv) {
  long n, i;
  if (argc == 2 && strcmp(argv[1], "check") == 0) {
    int k;
    must_run();
    for (k = 0; k < run.nrows; k++) {
      const Row *r = &run.rows[k];
      printf("row %.17e %.17e %.17e %.17e %d %d %d\n", r->t, r->y[0], r->y[1], r->y[2],
             r->is_root, r->roots[0], r->roots[1]);
    }
    printf("steps %ld\nrhs_evals %ld\nlin_setups %ld\nerr_test_fails %ld\n"
           "step_solve_fails %ld\nnonlin_iters %ld\nnonlin_conv_fails %ld\njac_evals %ld\n"
           "rhs_evals_jacobian %ld\nroot_evals %ld\nstab_lim_order_reductions %ld\n"
           "last_step %.17e\ncurrent_step %.17e\ninitial_step %.17e\nlast_order %d\n",
           run.nst, run.nfe, run.nsetups, run.netf, run.nsolvefails, run.nni, run.ncfn,
           run.nje, run.nfeLS, run.nge, run.nslred, run.hlast, run.hcur, run.hinused,
           run.qlast);
    return check_ans(&run) ? 2 : 0;
  }
  if (argc < 2 || argc > 3 || (n = strtol(argv[1], NULL, 10)) < 1 ||
      (argc == 3 && strcmp(argv[2], "each") != 0)) {
    fprintf(stderr, "usage: %s N [each] | %s check\n", argv[0], argv[0]);
    return 64;
  }
  if (argc == 2) {
    long long start, stop;
    for (i = 0; i < WARMUP; i++) must_run();
    start = now_ns();
    for (i = 0; i < n; i++) must_run();
    stop = now_ns();
    if (check_ans(&run)) return 2;
    printf("%lld\n", stop - start);
  } else {
    long long *times = malloc((size_t)n * sizeof *times);
    if (!times) return 1;
    for (i = 0; i < EACH_WARMUP; i++) must_run();
    for (i = 0; i < n; i++) {
      long long start = now_ns();
      must_run();
      times[i] = now_ns() - start;
    }
    if (check_ans(&run)) return 2;
    for (i = 0; i < n; i++) printf("%lld\n", times[i]);
    free(times);
  }
  return 0;
}
