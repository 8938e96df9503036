// Tsitouras' 5(4) pair: 7 stages, first same as last, with a free fourth-order interpolant.
// Ch. Tsitouras, "Runge-Kutta pairs of order 5(4) satisfying only the first column simplifying
// assumption", Computers & Mathematics with Applications 62 (2011) 770-775 (the coefficients to double
// precision; e holds b - b_hat, the interpolant's weights b_i(theta) = sum_k r_ik theta^k in expanded form).
#pragma once

namespace stepwise::tableau {

struct Tsitouras54 {
  static constexpr int stages = 7;
  static constexpr int order = 5;           // the solution advanced
  static constexpr int estimate_order = 4;  // the embedded one: the error estimate is O(h^5)
  static constexpr bool fsal = true;        // the last stage is f at the step's end
  static constexpr int dense_stages = 7;    // the interpolant takes the step's stages alone
  static constexpr double c[stages] = {0, 0.161, 0.327, 0.9, 0.9800255409045097, 1, 1};
  static constexpr double a[stages][stages] = {
      {},
      {0.161},
      {-0.008480655492356989, 0.335480655492357},
      {2.8971530571054935, -6.359448489975075, 4.3622954328695815},
      {5.325864828439257, -11.748883564062828, 7.4955393428898365, -0.09249506636175525},
      {5.86145544294642, -12.92096931784711, 8.159367898576159, -0.071584973281401, -0.028269050394068383},
      {0.09646076681806523, 0.01, 0.4798896504144996, 1.379008574103742, -3.290069515436081, 2.324710524099774},
  };
  static constexpr double b[stages] = {0.09646076681806523, 0.01, 0.4798896504144996, 1.379008574103742, -3.290069515436081, 2.324710524099774, 0};
  static constexpr double e[stages] = {-0.00178001105222577714, -0.0008164344596567469, 0.007880878010261995, -0.1447110071732629,
                                       0.5823571654525552,      -0.45808210592918697,   0.015151515151515152};
  // dense output: b_i(theta) = sum_k w[i][k] (theta - 1/2)^k, degree 4: the published weights in powers of
  // theta, re-expanded about the step's middle in exact rational arithmetic
  static constexpr int dense_degree = 4;
  static constexpr int dense_order = 4;  // the interpolant's: its local error is O(h^5)
  static constexpr double w[dense_stages][dense_degree + 1] = {
      {0.107412352300968725, -0.10530884977290235, 0.0265442488645105, 0.8070784663638694, -1.0530884977290216},
      {0.011356249999999995, 0.01499999999999998, -0.05085000000000002, -0.02, 0.1017},
      {0.3956090305604530875, 0.71983447562174935, -1.2453136428256264, -0.959779300828999, 2.490627285651253},
      {-0.344752143525935375, 2.068512861155613, 8.274051444622451, -2.758017148207484, -16.548102889244902},
      {1.316185364958165, -4.93510427315412, -23.68976098140964, 6.58013903087216, 47.37952196281928},
      {-1.017060854293652125, 3.487065786149654, 17.435328930748289, -4.64942104819956, -34.87065786149661},
      {0.03125, -0.25, -0.75, 1, 2.5},
  };
};

}  // namespace stepwise::tableau
