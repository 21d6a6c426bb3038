"""`python3 -m lambert` prints the module's version of the API and where it was loaded."""
import lambert

print(f"lambert from {lambert.__file__}; estimators {lambert.estimators()}, "
      f"solvers {lambert.solvers()}")
