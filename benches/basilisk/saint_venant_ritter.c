/* Basilisk's Saint-Venant solver (saint-venant.h) on the Ritter dam break, for the
   side-by-side comparison with granflow's orders 1 and 2 in docs/validation.md
   ("Second order: error against CPU time"). Not part of granflow's build or tests:
   it is compiled with Basilisk's own qcc, outside this repository.

   Set-up (scenarios/dam_break_dry.toml): x in [-2, 2.5] m, N cells, g = 9.81,
   flat bed, h = 1 m for x < 0 and dry beyond, at rest, CFL 0.5, to t = 0.3 s.
   Prints the L1 error of h against the exact Ritter solution, the front (the largest
   cell centre with h > 1 mm) and its lag behind the exact 1 mm contour, relative to
   that contour's distance from the dam, and the CPU time of the run (set-up included).

   Arguments: N [ORDER]; ORDER 2 (default) is Basilisk's default scheme (minmod-limited
   reconstruction, predictor-corrector in time), ORDER 1 the first-order scheme
   (gradient = zero). */

#include <time.h>
#include "grid/cartesian1D.h"
#include "saint-venant.h"

static clock_t start;

int main (int argc, char * argv[])
{
  start = clock();
  N = argc > 1 ? atoi (argv[1]) : 2048;
  if (argc > 2 && atoi (argv[2]) == 1)
    gradient = zero;
  G = 9.81;
  L0 = 4.5;
  X0 = -2.;
  CFL = 0.5;
  run();
}

event init (i = 0)
{
  foreach() {
    zb[] = 0.;
    h[] = x < 0. ? 1. : 0.;
    eta[] = h[];
  }
}

event end (t = 0.3)
{
  double c0 = sqrt (G), l1 = 0., front = -1e30;
  foreach() {
    double xi = x/t, exact = xi <= -c0 ? 1. : xi < 2.*c0 ? sq(2.*c0 - xi)/(9.*G) : 0.;
    l1 += fabs (h[] - exact)*Delta;
    if (h[] > 1e-3 && x > front)
      front = x;
  }
  double contour = t*(2.*c0 - 3.*sqrt (G*1e-3));
  fprintf (stderr, "N %d steps %d t %.6g L1 %.6e front %.6f lag %.6e cpu %.6f\n",
	   N, i, t, l1, front, (contour - front)/contour,
	   (double)(clock() - start)/CLOCKS_PER_SEC);
}
