/* Times the ball-finger kernel `mass_cqd_g` (M and C qd + g) against CasADi-generated C for
 * the same scene in one process: the same 1024 random states (q uniform in [-pi, pi], qd in
 * [-2, 2] rad/s), cycled in the same order; every function called through a pointer to a
 * separately compiled object (no inlining into the loop for either side); thread CPU time;
 * functions timed round-robin, 15 rounds, median reported. Outputs are checked to agree first.
 *
 * Compiled by run.sh once per scene with -DSCENE=<scene> -DNQ=<joints>. */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define CAT2(a, b) a##b
#define CAT(a, b) CAT2(a, b)
#define STR2(a) #a
#define STR(a) STR2(a)
#define HEADER STR(CAT(SCENE, _casadi.h))
#include HEADER

#define FUSED CAT(SCENE, _fused)
#define MASS CAT(SCENE, _mass)
#define RNEA CAT(SCENE, _rnea)
#define RUST CAT(CAT(bf_, SCENE), _mass_cqd_g)

void RUST(const double *q, const double *qd, double *m, double *v);

#define NSTATES 1024
#define ROUNDS 15

static double states_q[NSTATES][NQ], states_qd[NSTATES][NQ];

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static double uniform(double lo, double hi) {
  rng ^= rng << 13;
  rng ^= rng >> 7;
  rng ^= rng << 17;
  return lo + (hi - lo) * ((rng >> 11) * (1.0 / 9007199254740992.0));
}

static double now(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* Work arrays of one CasADi function. */
typedef struct {
  const casadi_real **arg;
  casadi_real **res;
  casadi_int *iw;
  casadi_real *w;
} Work;

static Work work(int (*sz)(casadi_int *, casadi_int *, casadi_int *, casadi_int *)) {
  casadi_int na, nr, ni, nw;
  sz(&na, &nr, &ni, &nw);
  Work k = {calloc(na + 1, sizeof(void *)), calloc(nr + 1, sizeof(void *)),
            calloc(ni + 1, sizeof(casadi_int)), calloc(nw + 1, sizeof(casadi_real))};
  return k;
}

static Work wf, wm, wr;
static double out_m[NQ * NQ], out_v[NQ];
static double cm[NQ * NQ], cv[NQ];

static void call_rust(int i) { RUST(states_q[i], states_qd[i], out_m, out_v); }
static void call_fused(int i) {
  wf.arg[0] = states_q[i];
  wf.arg[1] = states_qd[i];
  wf.res[0] = cm;
  wf.res[1] = cv;
  FUSED(wf.arg, wf.res, wf.iw, wf.w, 0);
}
static void call_two(int i) {
  wm.arg[0] = states_q[i];
  wm.res[0] = cm;
  MASS(wm.arg, wm.res, wm.iw, wm.w, 0);
  wr.arg[0] = states_q[i];
  wr.arg[1] = states_qd[i];
  wr.res[0] = cv;
  RNEA(wr.arg, wr.res, wr.iw, wr.w, 0);
}

typedef void (*Fn)(int);
static volatile double sink;

static double time_once(Fn f, long calls) {
  double t0 = now();
  for (long c = 0; c < calls; c++) f((int)(c & (NSTATES - 1)));
  double t = now() - t0;
  sink += out_m[0] + cm[0];
  return t / calls * 1e9;
}

static int cmp(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

int main(void) {
  for (int s = 0; s < NSTATES; s++)
    for (int j = 0; j < NQ; j++) {
      states_q[s][j] = uniform(-3.14159265358979323846, 3.14159265358979323846);
      states_qd[s][j] = uniform(-2.0, 2.0);
    }
  wf = work(CAT(FUSED, _work));
  wm = work(CAT(MASS, _work));
  wr = work(CAT(RNEA, _work));

  /* Agreement: max |rust - casadi| / max(1, |casadi|) over all states and outputs. */
  double err = 0.0;
  for (int s = 0; s < NSTATES; s++) {
    call_rust(s);
    call_fused(s);
    for (int i = 0; i < NQ; i++) {
      for (int j = 0; j < NQ; j++) {
        double c = cm[j * NQ + i]; /* CasADi: column-major */
        err = fmax(err, fabs(out_m[i * NQ + j] - c) / fmax(1.0, fabs(c)));
      }
      err = fmax(err, fabs(out_v[i] - cv[i]) / fmax(1.0, fabs(cv[i])));
    }
  }

  Fn fns[3] = {call_rust, call_fused, call_two};
  const char *names[3] = {"ball-finger mass_cqd_g", "CasADi fused (M, tau)", "CasADi M + RNEA"};
  double t[3][ROUNDS];
  /* Calls per timing: about 20 ms each on the calibration run. */
  double per = time_once(call_fused, 20000);
  long calls = (long)(2e7 / per);
  if (calls < NSTATES) calls = NSTATES;
  for (int f = 0; f < 3; f++) time_once(fns[f], calls); /* warm-up */
  for (int r = 0; r < ROUNDS; r++)
    for (int f = 0; f < 3; f++) t[f][r] = time_once(fns[f], calls);
  double med[3];
  for (int f = 0; f < 3; f++) {
    qsort(t[f], ROUNDS, sizeof(double), cmp);
    med[f] = t[f][ROUNDS / 2];
  }
  printf("%s (NQ = %d): outputs agree to %.1e (max relative difference)\n", STR(SCENE), NQ, err);
  for (int f = 0; f < 3; f++)
    printf("  %-24s %8.1f ns/call  [%.1f, %.1f]  ratio to fused %.2f\n", names[f], med[f],
           t[f][0], t[f][ROUNDS - 1], med[f] / med[1]);
  return err < 1e-12 ? 0 : 1;
}
