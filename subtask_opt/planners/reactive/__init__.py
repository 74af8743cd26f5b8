"""Reactive navigation with a sonar ring: fuzzy via-point selection, VFF, VFH.

* :mod:`.unicycle` - the differential-drive robot (exact arcs, limits);
* :mod:`.sonar` - the range-sensor ring, ray casting and scan prediction;
* :mod:`.fuzzy` - seed paper 001's fuzzy decision (eq. 1-7, Table 1, Saaty weights)
  and the fuzzy navigator;
* :mod:`.baselines` - VFF and VFH on the same ring;
* :mod:`.scenarios` - the paper's scenarios, seeded random worlds, scenario files;
* :mod:`.simulation` - the closed loop, the registered planners
  (``fuzzy``, ``fuzzy-no-escape``, ``vff``, ``vfh``) and the benchmark suite.
"""
