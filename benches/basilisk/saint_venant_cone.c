/* Cost per cell update of Basilisk's Saint-Venant solver (saint-venant.h) on a
   uniform Cartesian grid, for the side-by-side comparison with granflow's 2-D
   hydrostatic step in docs/performance.md. Not part of granflow's build or tests:
   it is compiled with Basilisk's own qcc, outside this repository.

   Set-up (the same as examples/hydrostatic_2d_cost.rs): a 4 m × 4 m square,
   x in [0, 4], y in [-2, 2], N × N cells, g = 9.81, the gentle bed
   z_b = 0.05 sin(2x) cos(y), a cone of thickness max(0, 0.5 − 0.3 r) at rest around
   (2, 0) (about 55 % of the cells wet), CFL 0.5, STEPS steps from rest, no output.

   Arguments: N STEPS [ORDER]; ORDER 2 (default) is Basilisk's default scheme
   (minmod-limited reconstruction, predictor-corrector in time), ORDER 1 the
   first-order scheme (no reconstruction slopes, one update per step). */

#include "grid/multigrid.h"
#include "saint-venant.h"

int STEPS = 10;

int main (int argc, char * argv[])
{
  int n = argc > 1 ? atoi (argv[1]) : 256;
  STEPS = argc > 2 ? atoi (argv[2]) : 10;
  if (argc > 3 && atoi (argv[3]) == 1)
    gradient = zero;
  G = 9.81;
  L0 = 4.;
  origin (0., -2.);
  CFL = 0.5;
  N = n;
  run();
}

event init (i = 0)
{
  foreach() {
    zb[] = 0.05*sin(2.*x)*cos(y);
    double r = sqrt (sq(x - 2.) + sq(y));
    h[] = max (0.5 - 0.3*r, 0.);
    eta[] = zb[] + h[];
  }
}

event stop (i = STEPS) {
  stats s = statsf (h);
  fprintf (stderr, "steps %d t %.6g h sum %.12g max %.6g\n", i, t, s.sum, s.max);
  return 1;
}
