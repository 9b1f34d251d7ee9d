"""What the tests share: a fake browser over the websocket (``wsclient``), readers of viser's private state
(``viser_private``), real-browser helpers (``browser``), screen geometry of the free-kick goal
(``screen_geometry``), reference IK solvers (``ik_reference``), a reference ball flight (``ball_reference``),
hypothesis strategies for a rider's quantities (``riders``), waiting on state (``waiting``), skipping or failing
on a missing capability (``ci``), a fresh Python process (``processes``), and the project's paths (``paths``)."""
