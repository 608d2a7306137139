"""Process plumbing: the sonar pipeline's worker processes, shared-memory frame transport, spawn guard, signal handling, garbage-collector policy."""
