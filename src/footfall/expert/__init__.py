"""The synthetic expert: its judgement of footholds, its corrections of run logs and the kinematic walker that collects its demonstrations."""
