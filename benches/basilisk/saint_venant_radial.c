/* Basilisk's Saint-Venant solver (saint-venant.h) on the radial collapse of
   scenarios/radial_collapse.toml, for the side-by-side comparison with granflow's
   orders 1 and 2 in docs/validation.md ("Basilisk side by side on the radial
   collapse"). Not part of granflow's build or tests: it is compiled with Basilisk's
   own qcc, outside this repository.

   Set-up (scenarios/radial_collapse.toml): [-1.5, 1.5]² m, N × N cells, walls on the
   four sides (Basilisk's default symmetry conditions), flat bed, g = 9.81, a column
   0.5 m high of radius 0.25 m at rest, CFL 0.45, to t = 1 s. Coulomb friction
   μ = tan 27° as granflow's friction step: after each hyperbolic step every wet
   cell's speed is reduced by Δt μ g, or set to 0 if it is smaller (the implicit
   Coulomb step on a flat bed).

   Arguments: N ORDER FILE [MU_DEG]; ORDER 2 is Basilisk's default scheme (minmod-limited
   reconstruction, predictor-corrector in time), ORDER 1 the first-order scheme
   (gradient = zero); MU_DEG the friction angle (default 27). Writes "x y h" of every cell at t = 1 s to FILE and prints
   the steps and the CPU time of the run (set-up included). */

#include <time.h>
#include "grid/cartesian.h"
#include "saint-venant.h"

static clock_t start;
static const char * path = "radial.txt";
static double mu;

int main (int argc, char * argv[])
{
  start = clock();
  N = argc > 1 ? atoi (argv[1]) : 40;
  if (argc > 2 && atoi (argv[2]) == 1)
    gradient = zero;
  if (argc > 3)
    path = argv[3];
  G = 9.81;
  L0 = 3.;
  origin (-1.5, -1.5);
  CFL = 0.45;
  mu = tan ((argc > 4 ? atof (argv[4]) : 27.)*M_PI/180.);
  run();
}

event init (i = 0)
{
  foreach() {
    zb[] = 0.;
    h[] = sq(x) + sq(y) < sq(0.25) ? 0.5 : 0.;
    eta[] = h[];
    u.x[] = u.y[] = 0.;
  }
}

/* Runs at the start of every iteration, i.e. after the previous step's update,
   with that step's Δt. */
event friction (i++)
{
  foreach() {
    double speed = sqrt (sq(u.x[]) + sq(u.y[]));
    double loss = dt*mu*G;
    if (h[] <= dry || speed <= loss)
      u.x[] = u.y[] = 0.;
    else {
      double keep = (speed - loss)/speed;
      u.x[] *= keep;
      u.y[] *= keep;
    }
  }
}

event end (t = 1.)
{
  double cpu = (clock() - start)/(double) CLOCKS_PER_SEC;
  FILE * fp = fopen (path, "w");
  foreach(serial)
    fprintf (fp, "%.9g %.9g %.17g\n", x, y, h[]);
  fclose (fp);
  printf ("N %d steps %d t %g cpu %g\n", N, i, t, cpu);
}
