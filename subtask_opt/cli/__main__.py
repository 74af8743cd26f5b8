"""``python -m subtask_opt.cli ...``: the same as the ``subtask-opt`` command."""

import sys

from subtask_opt.cli import main

sys.exit(main())
