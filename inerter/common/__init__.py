"""What every layer may use: the package's errors (:mod:`.errors`) and rotation math
(:mod:`.rotations`: quaternions, Z-X-Z Euler angles, axis-angle). Imports nothing of the package."""
