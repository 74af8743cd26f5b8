"""Robot descriptions (URDF + limit parameter files) shipped with subtask_opt."""
