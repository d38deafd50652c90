"""First-party roof builders for citygen."""
