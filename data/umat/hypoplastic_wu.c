/* The four-constant hypoplastic law of Wu and Bauer (1994) as an Abaqus UMAT in C, the same law
 * as rendulic's built-in hypoplastic_wu (docs/models.md, family 3), written the way such UMATs
 * usually are: one explicit (forward Euler) update per increment, in the authors'
 * tension-positive notation,
 *   dT = c1 tr(T) dE + c2 tr(T dE)/tr(T) T + (c3 T^2 + c4 T*^2)/tr(T) |dE|,
 * and the exact Jacobian of that update as DDSDDE (docs/umat.md).
 * PROPS(1..4) = c1..c4; optional PROPS(5) > 0: the largest |DSTRAN| accepted (a larger one gets
 * PNEWDT = 0.5); optional PROPS(6) > 0: the UMAT returns NaN once |STRAN + DSTRAN| exceeds it
 * (a model failing mid-path); optional PROPS(7) > 0: the new stress goes through a static
 * buffer, as in a Fortran UMAT with SAVE or COMMON variables, which is not thread-safe (a test
 * that the adapter calls one UMAT at a time); optional PROPS(8) > 0: no law, but STRESS(1..3) =
 * PROPS(8) for DTIME = 1 and -PROPS(8) for shorter increments, finite but, at 1e160, beyond the
 * range of their squares (a test of the driver's error estimate). STATEV is bookkeeping the tests read back: STATEV(1) = largest
 * accepted |DSTRAN|, STATEV(2) = STRAN(1) + DSTRAN(1); with NSTATV >= 7 STATEV(NSTATV) sums
 * DSTRAN(1) over the accepted increments.
 * Build: cc -O2 -fPIC -shared hypoplastic_wu.c -lm -o hypoplastic_wu.so */
#include <math.h>

/* Tensor (3x3) of a Voigt vector in Abaqus's order 11, 22, 33, 12, 13, 23; `shear` is 1 for
 * stresses and 1/2 for engineering strains. */
static void tensor(const double* v, double shear, double t[3][3]) {
  t[0][0] = v[0];
  t[1][1] = v[1];
  t[2][2] = v[2];
  t[0][1] = t[1][0] = shear * v[3];
  t[0][2] = t[2][0] = shear * v[4];
  t[1][2] = t[2][1] = shear * v[5];
}

static const int kRow[6] = {0, 1, 2, 0, 0, 1}, kCol[6] = {0, 1, 2, 1, 2, 2};

void umat(double* stress, double* statev, double* ddsdde, double* sse, double* spd, double* scd,
          double* rpl, double* ddsddt, double* drplde, double* drpldt, const double* stran,
          const double* dstran, const double* time, const double* dtime, const double* temp,
          const double* dtemp, const double* predef, const double* dpred, const char* cmname,
          const int* ndi, const int* nshr, const int* ntens, const int* nstatv, const double* props,
          const int* nprops, const double* coords, const double* drot, double* pnewdt,
          const double* celent, const double* dfgrd0, const double* dfgrd1, const int* noel,
          const int* npt, const int* layer, const int* kspt, const int* kstep, const int* kinc) {
  (void)sse, (void)spd, (void)scd, (void)rpl, (void)ddsddt, (void)drplde, (void)drpldt;
  (void)time, (void)dtime, (void)temp, (void)dtemp, (void)predef, (void)dpred, (void)cmname;
  (void)ndi, (void)nshr, (void)ntens, (void)coords, (void)drot, (void)celent, (void)dfgrd0;
  (void)dfgrd1, (void)noel, (void)npt, (void)layer, (void)kspt, (void)kstep, (void)kinc;
  if (*nprops >= 8 && props[7] > 0.0) {
    for (int i = 0; i < 36; ++i) ddsdde[i] = i % 7 == 0 ? 1.0 : 0.0;
    for (int i = 0; i < 3; ++i) stress[i] = (*dtime >= 1.0 ? 1.0 : -1.0) * props[7];
    return;
  }
  const double c1 = props[0], c2 = props[1], c3 = props[2], c4 = props[3];
  double T[3][3], D[3][3], E[3][3], T2[3][3], S2[3][3], N[3][3];
  tensor(stress, 1.0, T);
  tensor(dstran, 0.5, D);
  tensor(stran, 0.5, E);
  double norm = 0.0, total = 0.0, trT = T[0][0] + T[1][1] + T[2][2], trTD = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      norm += D[i][j] * D[i][j];
      total += (E[i][j] + D[i][j]) * (E[i][j] + D[i][j]);
      trTD += T[i][j] * D[i][j];
    }
  norm = sqrt(norm);
  total = sqrt(total);
  if (*nprops >= 5 && props[4] > 0.0 && norm > props[4]) {
    *pnewdt = 0.5;
    return;
  }
  double Td[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Td[i][j] = T[i][j] - (i == j ? trT / 3.0 : 0.0);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      T2[i][j] = S2[i][j] = 0.0;
      for (int k = 0; k < 3; ++k) {
        T2[i][j] += T[i][k] * T[k][j];
        S2[i][j] += Td[i][k] * Td[k][j];
      }
      N[i][j] = (c3 * T2[i][j] + c4 * S2[i][j]) / trT;
    }
  /* DDSDDE(i, j) = d dT_i / d DSTRAN_j (column-major): d dE_kl / d DSTRAN_j is 1 on the normal
   * components and 1/2 on each of the two entries of an engineering shear. */
  for (int j = 0; j < 6; ++j) {
    const double dj = D[kRow[j]][kCol[j]];
    for (int i = 0; i < 6; ++i) {
      const int a = kRow[i], b = kCol[i];
      double v = (i == j ? (i < 3 ? 1.0 : 0.5) : 0.0) * c1 * trT;
      v += c2 / trT * T[a][b] * T[kRow[j]][kCol[j]];
      if (norm > 0.0) v += N[a][b] * dj / norm;
      ddsdde[i + 6 * j] = v;
    }
  }
  double dT[6];
  for (int i = 0; i < 6; ++i) {
    const int a = kRow[i], b = kCol[i];
    dT[i] = c1 * trT * D[a][b] + c2 * trTD / trT * T[a][b] + N[a][b] * norm;
  }
  if (*nprops >= 7 && props[6] > 0.0) {
    static double saved[6];
    for (int i = 0; i < 6; ++i) saved[i] = stress[i] + dT[i];
    for (volatile int k = 0; k < 20000; ++k) {
    }
    for (int i = 0; i < 6; ++i) stress[i] = saved[i];
  } else {
    for (int i = 0; i < 6; ++i) stress[i] += dT[i];
  }
  if (*nprops >= 6 && props[5] > 0.0 && total > props[5]) stress[0] = NAN;
  if (*nstatv >= 1 && norm > statev[0]) statev[0] = norm;
  if (*nstatv >= 2) statev[1] = stran[0] + dstran[0];
  if (*nstatv >= 7) statev[*nstatv - 1] += dstran[0];
}
