"""`python3 -m lambert` prints where the module was loaded from and its estimator and solver names."""
import lambert

print(f"lambert from {lambert.__file__}; estimators {lambert.estimators()}, "
      f"solvers {lambert.solvers()}")
