/* The physical anchor for benchmarks/sweep.py: ik.solve's loop with method="dls" for a
   planar arm, one target at a time, in plain scalar C (built at bench time, loaded with
   ctypes). Same stop rules in the same order as ikteach/core/solve.py's advance():
   diverged (non-finite |e|), converged (|e| < tol, checked before stepping), stalled
   (last step's sum |dtheta| < stall_tol), max_iter; a non-finite step ends "diverged". */
#include <math.h>

enum { RUNNING, CONVERGED, STALLED, MAX_ITER, DIVERGED };

#define MAXJ 16

/* Solve targets[first:last]; writes status, iterations, final error; returns total iterations. */
long dls_sweep(const double *lengths, int n, const double *targets, const double *theta0,
               double tol, double damping, double stall_tol, int max_iter,
               long first, long last, int *status, int *iterations, double *error)
{
    long total = 0;
    double lam2 = damping * damping;
    for (long k = first; k < last; k++) {
        double th[MAXJ], c[MAXJ], s[MAXJ], jx[MAXJ], jy[MAXJ];
        for (int j = 0; j < n; j++) th[j] = theta0[j];
        double tx = targets[2 * k], ty = targets[2 * k + 1], last_step = INFINITY, err = 0;
        int i = 0, st = RUNNING;
        for (;;) {
            double phi = 0, x = 0, y = 0;
            for (int j = 0; j < n; j++) {
                phi += th[j];
                c[j] = lengths[j] * cos(phi);
                s[j] = lengths[j] * sin(phi);
                x += c[j];
                y += s[j];
            }
            double ex = tx - x, ey = ty - y;
            err = sqrt(ex * ex + ey * ey);
            if (!isfinite(err)) { st = DIVERGED; break; }
            if (err < tol) { st = CONVERGED; break; }
            if (i > 0 && last_step < stall_tol) { st = STALLED; break; }
            if (i >= max_iter) { st = MAX_ITER; break; }
            /* column j of J: z x (p_e - p_j) = (-(y_e - y_j), x_e - x_j): tail sums */
            double cx = 0, cy = 0;
            for (int j = n - 1; j >= 0; j--) {
                cx += c[j];
                cy += s[j];
                jx[j] = -cy;
                jy[j] = cx;
            }
            double a = lam2, b = 0, d = lam2;  /* J J^T + lambda^2 I = [[a, b], [b, d]] */
            for (int j = 0; j < n; j++) {
                a += jx[j] * jx[j];
                b += jx[j] * jy[j];
                d += jy[j] * jy[j];
            }
            double det = a * d - b * b;
            double ux = (d * ex - b * ey) / det, uy = (a * ey - b * ex) / det;
            double sum = 0, nt[MAXJ];
            int finite = 1;
            for (int j = 0; j < n; j++) {
                double delta = jx[j] * ux + jy[j] * uy;
                nt[j] = th[j] + delta;
                sum += fabs(delta);
                finite &= isfinite(nt[j]);
            }
            if (!finite) { st = DIVERGED; break; }
            for (int j = 0; j < n; j++) th[j] = nt[j];
            last_step = sum;
            i++;
        }
        status[k] = st;
        iterations[k] = i;
        error[k] = err;
        total += i;
    }
    return total;
}
