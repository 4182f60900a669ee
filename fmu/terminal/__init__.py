"""What the long commands write to a terminal or a log file while they work: progress bars."""
