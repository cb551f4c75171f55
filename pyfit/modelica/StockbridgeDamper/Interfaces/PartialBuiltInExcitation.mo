within StockbridgeDamper.Interfaces;
partial model PartialBuiltInExcitation "Built-in excitation (sine, linear or logarithmic sweep): the extending model adds excitation.y to its input"
  parameter Integer exc_type(min=0, max=3) = 0 "Built-in excitation, added to the model's input: 0 off, 1 sine, 2 linear sweep, 3 log sweep; where the model allows them (clamp motion), 4 linear and 5 log sweep with constant velocity amplitude exc_v0";
  parameter Real exc_amplitude = 1 "Amplitude of the built-in excitation, in the unit of the input it is added to";
  parameter Real exc_f_start(unit="Hz", min=0) = 0 "Sine frequency or sweep start frequency";
  parameter Real exc_f_end(unit="Hz", min=0) = 60 "Sweep end frequency (held afterwards)";
  parameter Real exc_rate(unit="Hz/s", min=0) = 0.5 "Linear sweep rate";
  parameter Real exc_octaves_per_minute(unit="1/min") = 1 "Logarithmic sweep rate";
  parameter Real exc_t_ramp(unit="s", min=0) = 0 "Smooth amplitude ramp-in time (0: none)";
  Sources.Excitation excitation(kind=exc_type, amplitude=exc_amplitude, f_start=exc_f_start, f_end=exc_f_end,
    rate=exc_rate, octaves_per_minute=exc_octaves_per_minute, t_ramp=exc_t_ramp) "Built-in excitation signal";
end PartialBuiltInExcitation;
