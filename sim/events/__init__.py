"""What the mission loop emits and how it keeps time: step records and the observer protocol, the one scheduler, the stage timer."""
