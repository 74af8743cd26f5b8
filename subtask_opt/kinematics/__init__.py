"""Robot kinematics that know no task: the planar 2R arm, any serial URDF chain, their
inverse kinematics, joint limits and the jerk-limited synchronised joint move."""
