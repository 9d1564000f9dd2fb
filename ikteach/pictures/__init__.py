"""Pictures: 2-D plots and animations, 3-D scenes, the lab demo, live maps, alt text.
Uses the core and characters; loaded on first use (ik.plot, ik.scene, ...)."""
