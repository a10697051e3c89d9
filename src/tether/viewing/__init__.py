"""Reading run folders back: the animation, the browser replay, and the commands that
animate, view and export a run folder."""
