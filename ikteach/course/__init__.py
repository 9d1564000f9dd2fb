"""The course's own tooling: notebook setup, header and strip, the course home, exercise
checks (check/), the exercise builder, grading and its sandbox (grading/)."""
