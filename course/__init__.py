"""Character kinematics reference library."""
