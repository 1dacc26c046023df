"""What the experiments share, written once: the seed plan, the result base, per-seed jobs,
configs of parts, map specs, worlds, episode records, figures and the report's sections."""
